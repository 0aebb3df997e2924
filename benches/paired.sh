#!/usr/bin/env bash
# Which of two bench binaries is faster, on a machine whose speed drifts by 10-20 % within minutes (the 2-core
# VMs this project is measured on): both run at the same time, one thread each, so that drift hits both alike,
# in PAIRS rounds, then again with their places swapped (one place was measured ~9 % slower than the other, for
# the same binary). The ratio NEW/OLD is the geometric mean of the two orders' ratios of mean user time, which
# cancels the places' bias. Differences under ~3 % are noise. Instruction counts (callgrind) say what a change
# does; this says whether it pays.
#
#   benches/paired.sh OLD_BENCH NEW_BENCH PAIRS [BENCH_ARGS...]
#
# e.g. benches/paired.sh /tmp/render-old target/release/deps/render-… 6 --only cesium --samples 4 --runs 10
# Each binary gets its own output directory as its first argument (the render and points benches take one).
set -euo pipefail
old=$1 new=$2 pairs=$3
shift 3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# One round: A and B at once, one thread each; prints their user seconds.
round() {
    (RAYON_NUM_THREADS=1 /usr/bin/time -f %U -o "$work/a" "$1" "$work/out-a" "${@:3}" >/dev/null) &
    (RAYON_NUM_THREADS=1 /usr/bin/time -f %U -o "$work/b" "$2" "$work/out-b" "${@:3}" >/dev/null) &
    wait
    echo "$(tail -1 "$work/a") $(tail -1 "$work/b")"
}

# Mean user seconds of A and B over PAIRS rounds.
means() {
    for _ in $(seq "$pairs"); do round "$@"; done | awk '{a += $1; b += $2} END {printf "%.4f %.4f\n", a / NR, b / NR}'
}

read -r o1 n1 < <(means "$old" "$new" "$@")
read -r n2 o2 < <(means "$new" "$old" "$@")
awk -v o1="$o1" -v n1="$n1" -v o2="$o2" -v n2="$n2" 'BEGIN {
    printf "old first: old %.3f s, new %.3f s\nnew first: new %.3f s, old %.3f s\n", o1, n1, n2, o2
    printf "new / old: %.3f\n", sqrt((n1 / o1) * (n2 / o2))
}'
