#!/usr/bin/env bash
# Installs what posemfa's build and tests need, skipping whatever is already there. Safe to run again.
#
#   rustup target wasm32-unknown-unknown
#   wasm-bindgen-cli (wasm-bindgen, wasm-bindgen-test-runner) of exactly the wasm-bindgen version in Cargo.lock
#       (cargo install, 2 minutes on a quiet 2-core machine, 11 under load; only when `wasm-bindgen --version` differs)
#   Debian chromium + chromium-driver (headless browser tests; skipped with --no-browser)
#   node_modules from package-lock.json (npm ci, only when missing or when package*.json changed)
#   .venv-python: a Python venv with maturin, numpy, pytest and trimesh (the Python package's test stage), and
#       Debian's blender + python3-numpy (the Blender add-on's test), each only when missing
#   .venv-fixtures: a Python venv with Pixar's usd-core (PyPI, pinned), with which tests/usd_real_size.rs writes
#       real-sized USD files when it runs (only when missing or of another version; Debian's python3-venv first
#       if `python3 -m venv` cannot make one)
#
# Nothing prompts: apt runs with DEBIAN_FRONTEND=noninteractive, every network step has a timeout.
# Usage: scripts/setup.sh [--no-browser]
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
export PATH="$HOME/.cargo/bin:$PATH"
export DEBIAN_FRONTEND=noninteractive
export CARGO_TERM_PROGRESS_WHEN=never

browser=1
for arg in "$@"; do
  case "$arg" in
    --no-browser) browser=0 ;;
    *) echo "setup.sh: unknown option $arg (known: --no-browser)" >&2; exit 2 ;;
  esac
done

step() { printf '[setup] %s\n' "$*"; }
die() { printf '[setup] ERROR: %s\n' "$*" >&2; exit 1; }

# ---------------------------------------------------------------- Rust
command -v cargo >/dev/null || die "cargo not found; install Rust with rustup (stable) first"
command -v rustup >/dev/null || die "rustup not found; the wasm32 target is added with rustup (stable toolchain)"

if rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown; then
  step "rust target wasm32-unknown-unknown: present"
else
  step "rust target wasm32-unknown-unknown: installing (rustup target add)"
  timeout 600 rustup target add wasm32-unknown-unknown || die "rustup target add wasm32-unknown-unknown failed"
fi

# the native tests check the code's formatting (tests/style.rs)
if rustup component list --installed 2>/dev/null | grep -q '^rustfmt'; then
  step "rustfmt: present"
else
  step "rustfmt: installing (rustup component add)"
  timeout 600 rustup component add rustfmt || die "rustup component add rustfmt failed"
fi

# ---------------------------------------------------------------- wasm-bindgen-cli
# The CLI must be the very version of the wasm-bindgen crate that Cargo.lock resolved (Cargo.toml pins it with =).
want_wb=$(awk '$0 == "name = \"wasm-bindgen\"" { getline; gsub(/version = |"/, ""); print; exit }' Cargo.lock)
[ -n "$want_wb" ] || die "cannot read the wasm-bindgen version from Cargo.lock"

tool_version() { timeout 20 "$1" --version 2>/dev/null | awk '{ print $2 }' || true; }
wb_ok() {
  [ "$(tool_version wasm-bindgen)" = "$want_wb" ] && [ "$(tool_version wasm-bindgen-test-runner)" = "$want_wb" ]
}

if wb_ok; then
  step "wasm-bindgen-cli $want_wb: present"
else
  have="$(tool_version wasm-bindgen)"
  step "wasm-bindgen-cli $want_wb: installing (cargo install, 2-11 min; found '${have:-none}')"
  mkdir -p "$HOME/.cargo"
  # One install at a time on a machine: a second setup waits for the first, then finds the tool there.
  (
    flock -w 3600 9 || die "timed out waiting for another wasm-bindgen-cli install"
    if ! wb_ok; then
      # Not --locked: its lock file asks for crate versions this registry mirror does not serve.
      timeout 1500 cargo install wasm-bindgen-cli --version "$want_wb" --force \
        || die "cargo install wasm-bindgen-cli --version $want_wb failed"
    fi
  ) 9>"$HOME/.cargo/.posemfa-wasm-bindgen-install.lock"
  wb_ok || die "wasm-bindgen $want_wb still not on PATH after the install (PATH=$PATH)"
fi

# ---------------------------------------------------------------- Chromium + chromedriver (Debian)
as_root() {
  if [ "$(id -u)" = 0 ]; then "$@"
  elif command -v sudo >/dev/null; then sudo -n "$@"
  else die "need root (or passwordless sudo) for: $*"
  fi
}

apt_install() {
  local opts=(-y -q -o DPkg::Lock::Timeout=600 -o Dpkg::Options::=--force-confdef -o Dpkg::Options::=--force-confold)
  if ! compgen -G '/var/lib/apt/lists/*_Packages*' >/dev/null; then
    step "apt: package lists are empty, running apt-get update"
    as_root env DEBIAN_FRONTEND=noninteractive timeout 600 apt-get update -q || die "apt-get update failed"
  fi
  if ! as_root env DEBIAN_FRONTEND=noninteractive timeout 1200 apt-get install "${opts[@]}" "$@" </dev/null; then
    step "apt: install failed, running apt-get update and trying once more"
    as_root env DEBIAN_FRONTEND=noninteractive timeout 600 apt-get update -q || die "apt-get update failed"
    as_root env DEBIAN_FRONTEND=noninteractive timeout 1200 apt-get install "${opts[@]}" "$@" </dev/null \
      || die "apt-get install $* failed"
  fi
}

if [ "$browser" = 1 ]; then
  if [ -x /usr/bin/chromium ] && [ -x /usr/bin/chromedriver ]; then
    step "chromium + chromedriver: present ($(timeout 20 /usr/bin/chromedriver --version 2>/dev/null | awk '{ print $2 }'))"
  else
    step "chromium + chromedriver: installing (apt-get install chromium chromium-driver, ~1 min)"
    apt_install chromium chromium-driver
    [ -x /usr/bin/chromium ] && [ -x /usr/bin/chromedriver ] || die "chromium/chromedriver not in /usr/bin after apt"
  fi
else
  step "chromium + chromedriver: skipped (--no-browser)"
fi

# ---------------------------------------------------------------- usd-core (test fixtures written at test time)
# tests/usd_real_size.rs has usd-core write 30 k-vertex .usda / .usdc / .usdz files (17 MB, not committed) and
# reads them; scripts/fixtures/make-usd-real-size.sh does the same by hand.
usd_core=26.11
venv=.venv-fixtures
# venv_with DIR LABEL PACKAGE...: a fresh venv in DIR (Debian's python3-venv installed when missing) with the
# packages pip-installed into it, tried twice.
venv_with() {
  local dir=$1 label=$2 ok=0
  shift 2
  if ! python3 -m venv --clear "$dir" >/dev/null 2>&1; then
    step "$label: python3 -m venv failed, installing Debian's python3-venv"
    apt_install python3-venv
    python3 -m venv --clear "$dir" || die "python3 -m venv $dir failed"
  fi
  for attempt in 1 2; do
    if timeout 900 "$dir/bin/python" -m pip install --quiet --disable-pip-version-check "$@" </dev/null; then
      ok=1; break
    fi
    step "$label: attempt $attempt failed"
  done
  [ "$ok" = 1 ] || die "pip install $* into $dir failed"
}
usd_core_version() {
  "$venv/bin/python" -c 'import pxr, importlib.metadata as m; print(m.version("usd-core"))' 2>/dev/null || true
}
if [ "$(usd_core_version)" = "$usd_core" ]; then
  step "usd-core $usd_core in $venv: present"
else
  step "usd-core $usd_core in $venv: installing (python3 -m venv, pip install usd-core==$usd_core, ~1 min)"
  command -v python3 >/dev/null || apt_install python3 python3-venv
  venv_with "$venv" "usd-core" "usd-core==$usd_core"
  [ "$(usd_core_version)" = "$usd_core" ] || die "$venv/bin/python cannot import pxr after installing usd-core"
fi

# ---------------------------------------------------------------- the Python package and Blender (test stage python)
# .venv-python: maturin (builds the wheel from pyproject.toml), numpy, pytest, trimesh (docs/python.md's example);
# scripts/test.sh python installs the package into it. Debian's blender + python3-numpy for the add-on's test
# (tests/python/test_blender.py; about 3 minutes to install, only when missing).
pyvenv=.venv-python
py_tools_ok() {
  "$pyvenv/bin/python" -c 'import maturin, numpy, pytest, trimesh' 2>/dev/null
}
if py_tools_ok; then
  step "python tools in $pyvenv (maturin, numpy, pytest, trimesh): present"
else
  step "python tools in $pyvenv: installing (python3 -m venv, pip install maturin numpy pytest trimesh, ~1 min)"
  venv_with "$pyvenv" "python tools" maturin numpy pytest trimesh
  py_tools_ok || die "$pyvenv/bin/python cannot import maturin, numpy, pytest and trimesh after installing them"
fi

if command -v blender >/dev/null && dpkg -s python3-numpy >/dev/null 2>&1; then
  step "blender + python3-numpy: present"
else
  step "blender + python3-numpy: installing (apt-get install blender python3-numpy, ~3 min)"
  apt_install blender python3-numpy
  command -v blender >/dev/null || die "blender not on PATH after apt"
fi

# ---------------------------------------------------------------- node_modules
command -v node >/dev/null && command -v npm >/dev/null || die "node and npm are needed (node >= 20.19)"
node -e 'const [a,b]=process.versions.node.split(".").map(Number); process.exit(a>20||(a===20&&b>=19)?0:1)' \
  || die "node $(node --version) is too old for vite 8: need >= 20.19"

stamp_file=node_modules/.posemfa-deps-stamp
stamp="$(cat package.json package-lock.json 2>/dev/null | sha256sum | cut -d' ' -f1) node-$(node --version)"
if [ -f "$stamp_file" ] && [ "$(cat "$stamp_file")" = "$stamp" ] \
   && [ -x node_modules/.bin/vite ] && [ -x node_modules/.bin/wasm-opt ] && [ -d node_modules/playwright-core ]; then
  step "node_modules: up to date"
else
  if [ -f package-lock.json ]; then
    step "node_modules: installing (npm ci)"
    cmd=(npm ci)
  else
    step "node_modules: installing (npm install, no package-lock.json)"
    cmd=(npm install)
  fi
  ok=0
  for attempt in 1 2; do
    if timeout 900 "${cmd[@]}" --no-audit --no-fund --loglevel=error </dev/null; then ok=1; break; fi
    step "node_modules: attempt $attempt failed"
  done
  [ "$ok" = 1 ] || die "${cmd[*]} failed"
  # npm ci takes package-lock.json as it is; hash again in case `npm install` just wrote it.
  stamp="$(cat package.json package-lock.json 2>/dev/null | sha256sum | cut -d' ' -f1) node-$(node --version)"
  printf '%s\n' "$stamp" >"$stamp_file"
fi

step "done"
