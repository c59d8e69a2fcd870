# Sourced (not run) by scripts/bench-dembones.sh and scripts/bench-rig.sh: sets $venv to a throwaway Python venv
# with the PyPI package py-dem-bones 0.13.1 and numpy (benchmark only, never a dependency of posemfa), made on
# first use: POSEMFA_DEMBONES_VENV, default /tmp/posemfa-dembones-venv. Its Python runs
# scripts/bench-dembones.py and scripts/bench-rig-dembones.py (which share scripts/dembones_common.py).
venv=${POSEMFA_DEMBONES_VENV:-/tmp/posemfa-dembones-venv}
if ! "$venv/bin/python" -c 'import py_dem_bones, numpy' 2>/dev/null; then
  echo "[$(basename "$0")] making $venv with py-dem-bones 0.13.1 (benchmark only)" >&2
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet 'py-dem-bones==0.13.1' numpy >&2
fi
