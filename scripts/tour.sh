#!/usr/bin/env bash
# The scripted screenshot tour of csw-workbench (docs/user-guide.md shows its output).
#   scripts/tour.sh [BUILD_DIR]      (default: build-gui; configured with CSW_BUILD_GUI=ON)
# Builds csw and csw-workbench, then runs the workbench offscreen: it writes a corpus
# holding its synthetic cued-speech take, imports the demo corpus's sentences (datasets/demo,
# made by the virtual cuer; generated with `csw simulate demo --seed 1` when absent) and the
# real Facial-Sing.c3d capture from ../shared/data when present, through the same background
# job as File > Import, drives the window and saves PNG screenshots into docs/screenshots/.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-gui}
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -G Ninja -DCSW_BUILD_GUI=ON >/dev/null
fi
cmake --build "$build" --target csw-workbench csw -j2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
demo=datasets/demo
if [ ! -f "$demo/sentences/markerset.json" ]; then
  demo=$work/demo
  "$build/workbench/cli/csw" simulate demo --seed 1 -o "$demo" >/dev/null
fi
captures=()
for f in "$demo"/sentences/sentence_00[1-3].{c3d,TextGrid,wav}; do
  [ -f "$f" ] && captures+=(--tour-capture "$f")
done
real=../shared/data/c3d/c3d.org/sample_29/Facial-Sing.c3d
if [ -f "$real" ]; then
  captures+=(--tour-capture "$real")
else
  echo "note: $real not found; the tour shows the synthetic take only" >&2
fi
QT_QPA_PLATFORM=${QT_QPA_PLATFORM:-offscreen} "$build/workbench/gui/csw-workbench" \
  --tour docs/screenshots --tour-work "$work" --tour-markerset "$demo/sentences/markerset.json" "${captures[@]}"
