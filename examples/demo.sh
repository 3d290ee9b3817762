#!/bin/sh
# The README's main job on the built-in defaults; `make demo` runs it with .venv/bin on PATH.
# Every step writes into out/ and may be re-run (--force).
set -eu
mkdir -p out
accugrid --version
