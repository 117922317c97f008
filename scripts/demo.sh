#!/usr/bin/env bash
# The main job on the embedded demo corpus, from a fresh Debian 12 machine (as root):
# installs missing packages, builds csw (Release), imports the demo corpus
# (datasets/demo, made by the virtual cuer) into out/demo/corpus.h5 and prints
# `csw info` of it. Regenerate the demo corpus with:
#   csw simulate demo --seed 1 -o datasets/demo
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache}
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release -DCSW_BUILD_TESTS=OFF -DCSW_BUILD_BENCH=OFF >/dev/null
cmake --build build/release -j"$(nproc)" --target csw
csw=build/release/workbench/cli/csw
demo=datasets/demo
if [ ! -f "$demo/sentences/markerset.json" ]; then
  echo "== demo corpus not found: generating it with the virtual cuer"
  "$csw" simulate demo --seed 1 -o "$demo"
fi
mkdir -p out/demo
rm -f out/demo/corpus.h5
echo "== csw import (shapes, visemes, sentences)"
for part in shapes visemes sentences; do
  shopt -s nullglob
  files=("$demo/$part"/*.c3d "$demo/$part"/*.TextGrid "$demo/$part"/*.wav)
  "$csw" import "${files[@]}" --markerset "$demo/$part/markerset.json" -o out/demo/corpus.h5
done
echo "== csw info out/demo/corpus.h5"
"$csw" info out/demo/corpus.h5
