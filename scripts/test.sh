#!/usr/bin/env bash
# Every test of posemfa, in order, stopping at the first stage that fails (what `npm test` runs after setup):
#   1. native        cargo test
#   2. wasm-node     cargo test --target wasm32-unknown-unknown --lib --test '*'   (wasm-bindgen-test-runner, Node)
#   3. wasm-chromium the same in headless Chromium (WASM_BINDGEN_USE_BROWSER=1, /usr/bin/chromedriver)
#   4. page          build:wasm + vite build into dist/ + the debug CLI, then `node --test tests/e2e/*.test.mjs`
#   5. python        the CLI + `pip install .` (the wheel, into .venv-python), then pytest tests/python:
#                    the Python package against the CLI, and the Blender add-on in headless Blender
# Needs what scripts/setup.sh installs.
# Every stage has a time limit of about 3-4x what it takes on a quiet 2-core machine (native 6 min, wasm-node
# 9, wasm-chromium 3, page build 3, page tests 7.5, python build 25 and tests 25; each page test at most 4 min), so that a hang fails that
# stage with its name well inside CI's 90 minutes instead of running out the clock.
# Usage: scripts/test.sh [STAGE...]   (default: all five; e.g. `npm test -- wasm-chromium page` for a subset)
#
# For the page tests (stage 4) this script serves dist/ with `vite preview` and exports:
#   POSEMFA_URL              http://127.0.0.1:PORT/ (the built page)
#   POSEMFA_CHROMIUM         /usr/bin/chromium (playwright-core: chromium.launch({ executablePath }))
#   POSEMFA_CHROMIUM_ARGS    the launch flags this closed network needs, space-separated
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
root=$(pwd)
export PATH="$HOME/.cargo/bin:$PATH"
export CARGO_TERM_PROGRESS_WHEN=never
export CARGO_TERM_COLOR=never
export NO_COLOR=1
# No incremental caches: a run of every stage builds each crate once or twice, and the caches only took disk
# (580 MB of target/debug/incremental).
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"

all_stages=(native wasm-node wasm-chromium page python)
stages=("$@")
[ "${#stages[@]}" -gt 0 ] || stages=("${all_stages[@]}")
for s in "${stages[@]}"; do
  case " ${all_stages[*]} " in *" $s "*) ;; *) echo "test.sh: unknown stage '$s' (stages: ${all_stages[*]})" >&2; exit 2 ;; esac
done
want() { case " ${stages[*]} " in *" $1 "*) return 0 ;; *) return 1 ;; esac; }

logdir=$(mktemp -d "${TMPDIR:-/tmp}/posemfa-test.XXXXXX")
server_pid=
cleanup() {
  if [ -n "$server_pid" ]; then kill "$server_pid" 2>/dev/null || true; wait "$server_pid" 2>/dev/null || true; fi
  rm -rf "$logdir"
}
trap cleanup EXIT

summary=()
total_pass=0
total_fail=0
total_ignored=0
t_all=$(date +%s)

banner() { printf '\n==================== [test %s] %s ====================\n' "$1" "$2"; disk; }

# What the build has taken and what is left: a full run fills about 1.5 GB of target/ (Cargo.toml, profile.dev).
disk() {
  local used free
  used=$(du -sh target 2>/dev/null | cut -f1 || true)
  free=$(df -Ph . | awk 'NR == 2 { print $4 }')
  printf '[test] disk: target/ %s, %s free\n' "${used:-0}" "$free"
}
free_kb=$(df -Pk . | awk 'NR == 2 { print $4 }')
if [ "${free_kb:-0}" -lt 3000000 ]; then
  printf '[test] WARNING: only %s MB free here; a full run needs about 2.5 GB (target/ and node_modules/)\n' "$(( free_kb / 1024 ))"
fi

# Counts from the closing lines of cargo test / wasm-bindgen-test-runner ("test result: ok. N passed; M failed;
# K ignored") and of node's test runner ("# pass N" / "ℹ pass N", "# skipped N").
# A Rust test that needs ../shared (POSEMFA_SHARED) and finds it absent returns early, so cargo counts it as
# passed; it prints "SKIPPED(needs ../shared): NAME" (tests/common/mod.rs, shared_dir), and each such line moves
# one test from passed to skipped; so does "SKIPPED(needs usd-core): NAME" (tests/usd_real_size.rs, without a
# Python with usd-core: scripts/setup.sh makes .venv-fixtures). Under CI=true those tests fail instead.
count() {
  awk '
    match($0, /test result: [A-Za-z]+\. [0-9]+ passed; [0-9]+ failed; [0-9]+ ignored/) {
      split(substr($0, RSTART, RLENGTH), w, /[ ;]+/); p += w[4]; f += w[6]; i += w[8]
    }
    /^(# |ℹ )pass [0-9]+/ { p += $3 }
    /^(# |ℹ )fail [0-9]+/ { f += $3 }
    /^(# |ℹ )skipped [0-9]+/ { i += $3 }
    /SKIPPED\(needs (\.\.\/shared|usd-core)\): / { s += 1 }
    # pytest (stage python): "==== 31 passed, 2 skipped in 95.1s ===="
    /^=+ .*[0-9]+ (passed|failed|skipped|error).* in [0-9.]+s/ {
      n = split($0, w, /[ ,]+/)
      for (k = 2; k <= n; k++) {
        if (w[k] == "passed") p += w[k - 1]
        if (w[k] == "failed" || w[k] == "error" || w[k] == "errors") f += w[k - 1]
        if (w[k] == "skipped") i += w[k - 1]
      }
    }
    END { print p - s, f + 0, i + s, s + 0 }
  ' "$1"
}

# run_stage NAME DESCRIPTION COMMAND...: runs, tees to a log, records counts and time; exits on failure.
run_stage() {
  local name=$1 desc=$2 t0 rc p f i s
  shift 2
  banner "$name" "$desc"
  t0=$(date +%s)
  set +e
  "$@" 2>&1 | tee "$logdir/$name.log"
  rc=${PIPESTATUS[0]}
  set -e
  read -r p f i s < <(count "$logdir/$name.log")
  total_pass=$(( total_pass + p )); total_fail=$(( total_fail + f )); total_ignored=$(( total_ignored + i ))
  local dt=$(( $(date +%s) - t0 ))
  if [ "$rc" != 0 ]; then
    summary+=("$(printf '%-14s FAILED (exit %s) after %4d s: %d passed, %d failed' "$name" "$rc" "$dt" "$p" "$f")")
    print_summary
    printf '\n[test] FAILED at stage %s: %s (exit %s)\n' "$name" "$desc" "$rc"
    exit 1
  fi
  if [ "$p" = 0 ]; then
    summary+=("$(printf '%-14s FAILED after %4d s: it ran no test' "$name" "$dt")")
    print_summary
    printf '\n[test] FAILED at stage %s: no test ran\n' "$name"
    exit 1
  fi
  if [ "$s" != 0 ] && [ "${CI:-}" = true ]; then
    summary+=("$(printf '%-14s FAILED after %4d s: %d tests skipped for want of ../shared or usd-core, and CI=true' "$name" "$dt" "$s")")
    print_summary
    printf '\n[test] FAILED at stage %s: ../shared (POSEMFA_SHARED) or usd-core (scripts/setup.sh) is absent in CI\n' "$name"
    exit 1
  fi
  local note=
  [ "$s" = 0 ] || note=" ($s need ../shared or usd-core, absent: SKIPPED lines above)"
  summary+=("$(printf '%-14s ok     %4d s: %d passed, %d failed, %d skipped%s' "$name" "$dt" "$p" "$f" "$i" "$note")")
}

print_summary() {
  printf '\n==================== [test] summary (%d s) ====================\n' "$(( $(date +%s) - t_all ))"
  printf '  %s\n' "${summary[@]}"
  disk
}

# ------------------------------------------------------------------ 1. native
if want native; then
  run_stage native "cargo test (native: lib, bin, tests/)" \
    timeout 1500 cargo test
fi

# ------------------------------------------------------------------ 2. wasm in Node
# --lib --test '*': the library's unit tests and tests/*.rs; not the CLI binary (native only).
wasm_test=(cargo test --target wasm32-unknown-unknown --lib --test '*')
if want wasm-node; then
  run_stage wasm-node "wasm32 tests in Node (wasm-bindgen-test-runner)" \
    timeout 1500 "${wasm_test[@]}"
fi

# ------------------------------------------------------------------ 3. wasm in headless Chromium
# Flags for Chromium on this closed network (no GPU; no background connections). None of them breaks WebGL2
# (see shared/TOOLCHAIN.md): never add --disable-software-rasterizer, --use-gl=swiftshader, --use-angle=gl.
chrome_args=(--disable-gpu --disable-quic --no-first-run --disable-background-networking
  --disable-component-update --disable-sync --disable-default-apps --disable-extensions)
if want wasm-chromium || want page; then
  [ -x /usr/bin/chromium ] && [ -x /usr/bin/chromedriver ] \
    || { echo "[test] /usr/bin/chromium or /usr/bin/chromedriver missing: run npm run setup"; exit 1; }
fi
if want wasm-chromium; then
  # wasm-bindgen-test-runner adds headless, no-sandbox and disable-dev-shm-usage itself; chromedriver gives
  # every session a fresh temporary profile (user-data-dir).
  node -e '
    const args = process.argv.slice(1);
    process.stdout.write(JSON.stringify({ "goog:chromeOptions": { binary: "/usr/bin/chromium", args } }, null, 2));
  ' -- "${chrome_args[@]}" >"$logdir/webdriver.json"
  run_stage wasm-chromium "wasm32 tests in headless Chromium (chromedriver)" \
    timeout 900 env WASM_BINDGEN_USE_BROWSER=1 CHROMEDRIVER=/usr/bin/chromedriver \
    WASM_BINDGEN_TEST_WEBDRIVER_JSON="$logdir/webdriver.json" \
    WASM_BINDGEN_TEST_DRIVER_TIMEOUT="${WASM_BINDGEN_TEST_DRIVER_TIMEOUT:-120}" \
    WASM_BINDGEN_TEST_TIMEOUT="${WASM_BINDGEN_TEST_TIMEOUT:-1200}" \
    "${wasm_test[@]}"
fi

# ------------------------------------------------------------------ 4. page
if want page; then
  banner page "build:wasm + vite build, then Playwright page tests (tests/e2e/*.test.mjs)"
  t0=$(date +%s)
  # The CLI the page tests run (gltf, pose, pose-cli, rig) is built here, outside any test's time limit: after
  # stage native it is there already (the native dev-dependencies change no feature: Cargo.toml), but the page
  # stage alone builds it, which can take minutes on a loaded machine.
  if ! { timeout 900 bash scripts/build-wasm.sh && timeout 300 node_modules/.bin/vite build --logLevel warn \
    && timeout 900 cargo build --quiet --bin posemfa; }; then
    summary+=("$(printf '%-14s FAILED after %4d s: build:wasm, vite build or the CLI' page "$(( $(date +%s) - t0 ))")")
    print_summary
    printf '\n[test] FAILED at stage page: build:wasm, vite build or cargo build --bin posemfa\n'
    exit 1
  fi
  [ -f dist/index.html ] || { echo "[test] vite build wrote no dist/index.html"; exit 1; }
  echo "[test] dist/: $(find dist -type f | wc -l) files, $(du -sh dist | cut -f1)"
  summary+=("$(printf '%-14s ok     %4d s: build:wasm + vite build (dist/) + CLI' page-build "$(( $(date +%s) - t0 ))")")

  shopt -s nullglob
  e2e=(tests/e2e/*.test.mjs)
  shopt -u nullglob
  if [ "${#e2e[@]}" = 0 ]; then
    echo "[test] no page tests yet (tests/e2e/*.test.mjs): only the wasm and page builds were checked"
    summary+=("$(printf '%-14s none yet: no tests/e2e/*.test.mjs' page-e2e)")
  else
    port=$(node -e 'const s = require("net").createServer().listen(0, "127.0.0.1", () => { console.log(s.address().port); s.close(); })')
    node_modules/.bin/vite preview --host 127.0.0.1 --port "$port" --strictPort >"$logdir/preview.log" 2>&1 &
    server_pid=$!
    up=0
    for _ in $(seq 1 150); do
      if node -e "fetch('http://127.0.0.1:$port/').then(r => process.exit(r.ok ? 0 : 1), () => process.exit(1))"; then
        up=1; break
      fi
      kill -0 "$server_pid" 2>/dev/null || break
      sleep 0.2
    done
    [ "$up" = 1 ] || { cat "$logdir/preview.log"; echo "[test] vite preview did not serve dist/ on port $port"; exit 1; }
    export POSEMFA_URL="http://127.0.0.1:$port/"
    export POSEMFA_CHROMIUM=/usr/bin/chromium
    export POSEMFA_CHROMIUM_ARGS="--headless --no-sandbox ${chrome_args[*]}"
    echo "[test] serving dist/ at $POSEMFA_URL; ${#e2e[@]} page test file(s)"
    # node's test runner, one file after another (each may launch Chromium; 2 cores).
    run_stage page-e2e "Playwright page tests: ${e2e[*]}" \
      timeout 1200 node --test --test-concurrency=1 --test-timeout=240000 "${e2e[@]}"
    kill "$server_pid" 2>/dev/null || true; wait "$server_pid" 2>/dev/null || true; server_pid=
  fi
fi

# ------------------------------------------------------------------ 5. python
# The CLI the tests compare with (the dev build the other stages made: its fits are the release build's, number
# for number, and a release build with LTO would add minutes to CI), the package built by maturin from
# pyproject.toml (profile python, target/python/) and installed into .venv-python (scripts/setup.sh), then
# pytest: tests/python/ (the API, bad input, horse-poses against the CLI, trimesh, the Blender add-on in
# headless Blender).
if want python; then
  banner python "CLI + pip install . (.venv-python), then pytest tests/python"
  t0=$(date +%s)
  [ -x .venv-python/bin/python ] || { echo "[test] .venv-python missing: run npm run setup"; exit 1; }
  if ! { timeout 1500 cargo build --quiet --bin posemfa \
    && timeout 1500 env PATH="$root/.venv-python/bin:$PATH" .venv-python/bin/python -m pip install --quiet \
      --disable-pip-version-check --no-build-isolation --force-reinstall --no-deps . </dev/null; }; then
    summary+=("$(printf '%-14s FAILED after %4d s: the CLI or pip install .' python-build "$(( $(date +%s) - t0 ))")")
    print_summary
    printf '\n[test] FAILED at stage python: cargo build --bin posemfa or pip install .\n'
    exit 1
  fi
  summary+=("$(printf '%-14s ok     %4d s: CLI + wheel installed' python-build "$(( $(date +%s) - t0 ))")")
  run_stage python "pytest tests/python (the package, the Blender add-on)" \
    timeout 1500 env POSEMFA_CLI="$root/target/debug/posemfa" \
    .venv-python/bin/python -m pytest -p no:cacheprovider -ra -v tests/python
fi

print_summary
echo
echo "all stages passed"
echo "total: ${total_pass} passed, ${total_fail} failed, ${total_ignored} skipped"
