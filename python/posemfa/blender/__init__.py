"""The Blender add-on: ``python -m posemfa.blender OUT.zip`` writes it (docs/blender.md).

The zip holds a folder ``posemfa_rig/`` that Blender installs from Edit > Preferences > Add-ons > Install: its
``__init__.py`` (the add-on's ``bl_info``, then the operator from :mod:`posemfa.blender.addon`) and a copy of
this installed package (``posemfa_rig/posemfa/``: the compiled extension, abi3, so one build serves Blender's
Python 3.11 as it serves any CPython 3.9+, and the pure-Python modules). Blender's own numpy is used.
"""

import os
import zipfile

ADDON = "posemfa_rig"

_INIT = '''# posemfa: learn a rig from the animation of the active mesh (written by `python -m posemfa.blender`).
bl_info = {
    "name": "posemfa: learn a rig from an animation",
    "author": "posemfa",
    "version": (%(version)s),
    "blender": (3, 4, 0),
    "location": "3D Viewport > Object > posemfa: Learn Rig; F3 'Learn Rig'",
    "description": "Fits rigid parts to the mesh's animation and builds an armature, weights and an action that "
                   "reproduce it",
    "category": "Rigging",
}

from .posemfa.blender.addon import register, unregister  # noqa: E402,F401
'''


def package_dir():
    """The installed posemfa package (the folder the zip copies)."""
    return os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def write_addon(out):
    """Writes the add-on zip to ``out``; returns the list of files it holds."""
    from .. import __version__
    src = package_dir()
    if not any(n.startswith("_posemfa") and n.endswith((".so", ".pyd")) for n in os.listdir(src)):
        raise FileNotFoundError(f"no compiled extension (_posemfa*.so) in {src}: install the package with "
                                "`pip install .` first")
    version = ", ".join(str(int(x)) for x in __version__.split(".")[:3])
    names = []
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr(f"{ADDON}/__init__.py", _INIT % {"version": version})
        names.append(f"{ADDON}/__init__.py")
        for root, dirs, files in os.walk(src):
            dirs[:] = sorted(d for d in dirs if d != "__pycache__")
            for f in sorted(files):
                if f.endswith((".pyc", ".pyo")):
                    continue
                path = os.path.join(root, f)
                arc = os.path.join(ADDON, "posemfa", os.path.relpath(path, src))
                z.write(path, arc)
                names.append(arc)
    return names
