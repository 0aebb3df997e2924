#!/usr/bin/env bash
# Builds MPEG's pc_error (mpeg-pcc-dmetric 0.14.1) from its public source, the reference `vvgen compare` is held
# to on point clouds (benches/pc_error_reference.py, docs/benchmarks.md). Needs git and g++ (no cmake: the five
# sources compile in one command). Never run by the tests: they hold the figures it printed.
#
#   benches/pc_error_build.sh [DIR]    # default /tmp/pcerr; the binary is DIR/pc_error
set -euo pipefail
dir=${1:-/tmp/pcerr}
mkdir -p "$dir"
if [ ! -d "$dir/src" ]; then
    # A public mirror of the MPEG repository (mpeg-pcc-dmetric is hosted on MPEG's GitLab).
    git clone -q --depth 1 https://github.com/minhkstn/mpeg-pcc-dmetric "$dir/src"
fi
cd "$dir/src/source"
g++ -O2 -fopenmp -std=c++11 -I../dependencies -I../dependencies/program-options-lite -I. \
    main.cpp pcc_distortion.cpp pcc_processing.cpp clockcom.cpp \
    ../dependencies/program-options-lite/program_options_lite.cpp -o "$dir/pc_error"
"$dir/pc_error" 2>&1 | head -1
