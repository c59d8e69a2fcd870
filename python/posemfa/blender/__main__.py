"""python -m posemfa.blender OUT.zip: writes the Blender add-on (install it from Blender's preferences)."""

import sys

from . import write_addon


def main(argv):
    if len(argv) != 1 or argv[0].startswith("-"):
        print("usage: python -m posemfa.blender OUT.zip\n  writes the Blender add-on (Edit > Preferences > "
              "Add-ons > Install..., then enable 'posemfa: learn a rig from an animation')", file=sys.stderr)
        return 2
    try:
        names = write_addon(argv[0])
    except (OSError, FileNotFoundError) as e:
        print(f"posemfa.blender: {e}", file=sys.stderr)
        return 1
    print(f"wrote {argv[0]} ({len(names)} files)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
