#!/bin/sh
# umbra's GPU bundle: the catalogue on every hardware backend of this machine, judged by the
# specs alone (no goldens: a GPU umbra has never seen has none), in one command.
#
#   ./run.sh [--out DIR] [--backend ID]... [--loaders DIR] [-- MORE UMBRA CONFORMANCE ARGS]
#
# --backend  the ids to run (default: hw, every hardware EGL device and wgpu adapter;
#            `./umbra backends` lists them; gl33/swrast is Mesa's software EGL device)
# --loaders  a folder of the GL/Vulkan loaders' .deb files (libvulkan1 libegl1 libglvnd0
#            libopengl0 libgl1 libglx0 libgles2) for a machine that lacks them: unpacked into
#            .root/ beside this script, no root needed (default: loaders/ beside it, if any)
# --out      where the results go (default: results/ beside this script)
#
# Leaves in OUT: report.json, results.csv, drivers.txt (the drivers, as the GL and Vulkan
# implementations report themselves), failures.csv, junit.xml, backends.txt (what
# `umbra backends` found), cards.txt and cards.json (each backend's behaviour card: what its
# driver chose inside the specs' freedom) and run.log; OUT/run/latest/ holds report.html and
# the pictures.
# Exit status: umbra conformance's (0 as expected, 1 a failure, 125 nothing could run, 130 interrupted).
set -u
# Ids and paths are taken as they are: no pathname expansion of a glob-like id.
set -f
here=$(cd "$(dirname "$0")" && pwd)
out="$here/results"
loaders="$here/loaders"
backends=""
need() {
    if [ $# -lt 2 ]; then
        echo "run.sh: $1 needs a value (see ./run.sh --help)" >&2
        exit 125
    fi
}
while [ $# -gt 0 ]; do
    case "$1" in
        --out) need "$@"; out="$2"; shift 2 ;;
        --backend) need "$@"; backends="$backends --backend $2"; shift 2 ;;
        --loaders) need "$@"; loaders="$2"; shift 2 ;;
        --) shift; break ;;
        -h|--help) sed -n '2,19p' "$0"; exit 0 ;;
        *) echo "run.sh: unknown argument $1 (see ./run.sh --help)" >&2; exit 125 ;;
    esac
done
[ -n "$backends" ] || backends="--backend hw"
mkdir -p "$out" || exit 125
out=$(cd "$out" && pwd)
# Nothing of an earlier run may pass for this one's.
rm -f "$out/.rc" "$out/report.json" "$out/results.csv" "$out/drivers.txt" \
    "$out/failures.csv" "$out/junit.xml" "$out/backends.txt" "$out/run.log" \
    "$out/cards.txt" "$out/cards.json"
rm -f "$out/run/latest"
trap 'echo "run.sh: interrupted" >&2; exit 130' INT TERM

# The loaders, where the machine has none of its own.
unpacked=0
set +f
for f in "$loaders"/*.deb; do
    [ -f "$f" ] || continue
    dpkg-deb -x "$f" "$here/.root" || exit 125
    unpacked=$((unpacked + 1))
done
set -f
if [ "$unpacked" -gt 0 ]; then
    lib="$here/.root/usr/lib/x86_64-linux-gnu:$here/.root/lib/x86_64-linux-gnu"
    export LD_LIBRARY_PATH="$lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    echo "run.sh: $unpacked loader packages from $loaders unpacked into $here/.root"
fi
# NVIDIA's ICD and EGL vendor files where a container keeps them outside the loaders' paths.
for f in /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json; do
    if [ -f "$f" ] && [ -z "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}" ]; then
        export VK_DRIVER_FILES="$f"
    fi
done
for f in /usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json; do
    if [ -f "$f" ] && [ -z "${__EGL_VENDOR_LIBRARY_FILENAMES:-}" ]; then
        export __EGL_VENDOR_LIBRARY_FILENAMES="$f"
    fi
done

started=$(date +%s)
"$here/umbra" backends > "$out/backends.txt" 2>&1
echo "run.sh: backends found (also in $out/backends.txt):"
sed -n '/^Backends/,/^$/p' "$out/backends.txt" | grep -E '^  [a-z]' || cat "$out/backends.txt"
# shellcheck disable=SC2086 # $backends is a list of flags.
{
    "$here/umbra" conformance $backends --golden none \
        --cases "$here/cases" --expectations "$here/expectations" \
        --out "$out/run" --judge-cache "$out/cache" --timeout 60 "$@" 2>&1
    echo $? > "$out/.rc"
} | tee "$out/run.log"
rc=$(cat "$out/.rc" 2>/dev/null || echo 125)
# umbra's four codes (docs/ci.md#exit-codes): a death by a signal (128 + N) could not run.
case "$rc" in 0 | 1 | 125 | 130) ;; *) rc=125 ;; esac
# The cards, kept: the first thing a driver developer asks of a GPU umbra has never seen.
# shellcheck disable=SC2086
"$here/umbra" card $backends --timeout 120 > "$out/cards.txt" 2>&1
# shellcheck disable=SC2086
"$here/umbra" card $backends --timeout 120 --json > "$out/cards.json" 2>> "$out/cards.txt"
latest="$out/run/latest"
if [ -d "$latest" ]; then
    for f in report.json results.csv drivers.txt failures.csv junit.xml; do
        if [ -f "$latest/$f" ]; then cp "$latest/$f" "$out/$f"; fi
    done
else
    echo "run.sh: no complete run under $out/run (see $out/run.log)" >&2
fi
echo "run.sh: $(($(date +%s) - started)) s; results in $out (report.json, results.csv, drivers.txt)"
exit "$rc"
