#!/usr/bin/env bash
# The main job on the embedded demo corpus, from a fresh Debian 12 machine (as root):
# installs missing packages, builds csw (Release) and runs `csw demo -o out/demo`
# on the demo corpus (datasets/demo, made by the virtual cuer): imports it into
# out/demo/corpus.h5, fits the face and hand models on the first third of the
# sentences (out/demo/models.h5), inverts them on every sentence, fills the gaps
# as new takes, trains the key recogniser on the labelled targets of the filled
# training sentences (out/demo/keys.h5), scores every filled sentence, measures
# the phasing, builds the synthesis dictionaries (out/demo/dict.h5) and
# synthesises 3 new sentences (out/demo/say: speech, cues, markers, point-light
# video), with the figures in out/demo/figures and everything on one page,
# out/demo/report/index.html; prints `csw info` of the corpus; then fits Öhman's
# coarticulation model on the viseme takes and generates a new phone string
# (out/demo/coartic), and runs the sign-language tools on the virtual signer
# (out/demo/signs: simulate, segment, transitions and their duration models, a
# new sign sequence as BVH).
# It ends by printing the page to open in a browser and the command that opens
# the corpus in csw-workbench.
# Regenerate the demo
# corpus with:
#   csw simulate demo --seed 1 -o datasets/demo
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache}
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release -DCSW_BUILD_TESTS=OFF -DCSW_BUILD_BENCH=OFF >/dev/null
cmake --build build/release -j"$(nproc)" --target csw
# The desktop app and the figures module, when Qt6 is there (install-deps.sh installs it).
if cmake --build build/release --target help 2>/dev/null | grep -q 'csw-workbench'; then
  cmake --build build/release -j"$(nproc)" --target csw-workbench csw_figures
fi
csw=build/release/workbench/cli/csw
demo=datasets/demo
if [ ! -f "$demo/sentences/markerset.json" ]; then
  echo "== demo corpus not found: generating it with the virtual cuer"
  "$csw" simulate demo --seed 1 -o "$demo"
fi
mkdir -p out/demo
echo "== csw demo: import, fit, invert, keys, phasing, dictionaries and 3 synthesised sentences (out/demo)"
"$csw" demo --source "$demo" -o out/demo
echo "== csw info out/demo/corpus.h5"
"$csw" info out/demo/corpus.h5
echo "== csw coartic fit on the viseme takes, then csw coartic generate a new phone string (out/demo/coartic)"
mkdir -p out/demo/coartic
"$csw" coartic fit out/demo/corpus.h5 --models out/demo/models.h5 --takes 'visemes*' \
  -o out/demo/coartic/ohman.json --figures out/demo/coartic
"$csw" coartic generate out/demo/coartic/ohman.json --phones "_ a p a _ i s i _ u l u _" \
  -o out/demo/coartic/generated.csv --figures out/demo/coartic
echo "== sign language on the virtual signer (out/demo/signs): simulate, segment, transitions, a new sequence"
rm -rf out/demo/signs
"$csw" simulate signs --count 30 --seed 1 -o out/demo/signs
"$csw" segment out/demo/signs/signs.h5 --tier manual
"$csw" transitions out/demo/signs/signs.h5 --tiers manual_right,manual_left \
  -o out/demo/signs/durations_per_hand.json --figures out/demo/signs/figures_per_hand
"$csw" transitions out/demo/signs/signs.h5 --tiers signs --joints all \
  -o out/demo/signs/durations.json --figures out/demo/signs/figures
"$csw" sign-sequence out/demo/signs/signs.h5 --glosses HELLO,MUSEUM,TO_PAY,SWIMMING_POOL \
  --durations out/demo/signs/durations.json -o out/demo/signs/sequence/hello_museum.bvh
if [ -x build/release/workbench/gui/csw-workbench ]; then
  echo "== open the demo corpus in the desktop app:"
  echo "   build/release/workbench/gui/csw-workbench out/demo/corpus.h5"
fi
echo "== the report of the whole pipeline, to open in a browser:"
echo "   $(pwd)/out/demo/report/index.html"
