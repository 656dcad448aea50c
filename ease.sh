#!/usr/bin/env bash
# EASE entry point: `./ease.sh demo` runs the demo, `./ease.sh test` runs the tests.
# Each sets up .venv/ at the repo root first (reused while requirements.txt and
# pyproject.toml are unchanged). Any other arguments go to the `ease` CLI.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$ROOT"
PY="${EASE_PYTHON:-python3.11}"
VENV="$ROOT/.venv"
STAMP="$VENV/.ease-deps"
want="$(cat requirements.txt pyproject.toml | sha256sum | cut -d' ' -f1)"
if [[ ! -x "$VENV/bin/python" || ! -f "$STAMP" || "$(cat "$STAMP")" != "$want" ]]; then
    echo "[ease] setting up $VENV (first run or changed dependencies)..." >&2
    command -v "$PY" >/dev/null || { echo "[ease] error: $PY not found; EASE needs Python 3.11 exactly (bpy 5.0.1)." >&2; exit 2; }
    rm -rf "$VENV"
    "$PY" -m venv "$VENV"
    "$VENV/bin/python" -m pip install --quiet --upgrade pip
    "$VENV/bin/python" -m pip install --quiet -r requirements.txt
    "$VENV/bin/python" -m pip install --quiet --no-deps -e .
    echo "$want" > "$STAMP"
fi
export WARP_CACHE_PATH="${WARP_CACHE_PATH:-$ROOT/.cache/warp}"
cmd="${1:-demo}"; shift || true
case "$cmd" in
    demo) exec "$VENV/bin/ease" demo "$@" ;;
    test) exec "$VENV/bin/python" -m pytest -n "${EASE_TEST_WORKERS:-auto}" --maxprocesses 8 --dist loadfile "$@" ;;
    *)    exec "$VENV/bin/ease" "$cmd" "$@" ;;
esac
