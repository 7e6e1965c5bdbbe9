#!/usr/bin/env bash
# The CUDA backend's device check (issue 20) as one prepared script: the GPU equivalence tests
# (GPU against the CPU path, byte for byte), compute-sanitizer (memcheck, racecheck) on them, and
# the GPU benchmarks beside the CPU path in the same run; a report with the GPU model, driver and
# date goes into a folder.
#
#   bash scripts/gpu_check.sh [--out DIR]
#       On a machine with ROS (scripts/setup.sh), nvcc and a GPU: builds with CUDA, then checks.
#   bash scripts/gpu_check.sh --bundle DIR
#       Here, on a machine with nvcc but maybe no GPU: builds with CUDA and packs the GPU test and
#       benchmark executables with the libraries they need (not CUDA's driver) into DIR, for a
#       bare GPU machine without ROS, OpenCV or the workspace's build (the device tool: carry DIR).
#   bash scripts/gpu_check.sh --from-bundle DIR [--out DIR]
#       On that GPU machine, in a copy of this repository: runs the check from the bundle.
#
# Without a usable GPU every GPU test skips and says why, and the report says so: the script
# itself still exits 0 unless a test fails, the build fails or the sanitizer finds an error.
# Environment: TABLETOP_CUDA_DEVICE picks the device (cuda_device.h); SANITIZER=0 skips
# compute-sanitizer (it multiplies the tests' run time by ~10-50).
set -uo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
MODE=build BUNDLE="" OUT=""
while [ $# -gt 0 ]; do
  case "$1" in
    --bundle) MODE=bundle; BUNDLE="$2"; shift 2 ;;
    --from-bundle) MODE=from_bundle; BUNDLE="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    *) echo "gpu_check: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
OUT="${OUT:-${ROOT}/gpu_check_$(date -u +%Y%m%d_%H%M%S)}"

# The GPU tests and benchmarks by executable; a test executable's gtest filter after ':'.
GPU_TESTS=(
  psfs_reconstruction/test_cuda_device
  psfs_reconstruction/test_gpu_fusion
  psfs_reconstruction/test_gpu_pixel_stage
  "psfs_reconstruction/test_reconstructor:*Cuda*"
  body_tracking/test_gpu_particle_weights
)
GPU_BENCHES=(
  psfs_reconstruction/bench_gpu_fusion
  body_tracking/bench_gpu_papf
)

build_with_cuda() {
  echo "[gpu_check] building the workspace with the CUDA backend"
  CUDACXX="${CUDACXX:-/usr/local/cuda/bin/nvcc}" bash "$ROOT/scripts/setup.sh" -DTABLETOP_CUDA=ON || exit 1
  # shellcheck disable=SC1091
  set +u; source "$ROOT/devel/setup.bash"; set -u
  local targets=()
  for t in "${GPU_TESTS[@]}" "${GPU_BENCHES[@]}"; do targets+=("$(basename "${t%%:*}")"); done
  (cd "$ROOT" && PATH=/usr/bin:$PATH catkin_make -j2 "${targets[@]}" 2>&1 | tail -3) || exit 1
}

if [ "$MODE" = bundle ]; then
  build_with_cuda
  rm -rf "$BUNDLE"; mkdir -p "$BUNDLE/bin" "$BUNDLE/lib"
  for t in "${GPU_TESTS[@]}" "${GPU_BENCHES[@]}"; do
    exe="$ROOT/devel/lib/${t%%:*}"
    if [ -x "$exe" ]; then cp "$exe" "$BUNDLE/bin/"; else echo "[gpu_check] not built: ${t%%:*}"; fi
  done
  # Every shared library they load except the C runtime and the NVIDIA driver, which the GPU
  # machine has (newer glibc reads older binaries; the driver must match the kernel module).
  for exe in "$BUNDLE"/bin/*; do
    ldd "$exe" | awk '/=> \//{print $3}'
  done | sort -u | grep -v -E '/(libc|libm|libdl|libpthread|librt|ld-linux[^/]*|libcuda)\.so' |
    while read -r lib; do cp -L "$lib" "$BUNDLE/lib/"; done
  echo "$ROOT" > "$BUNDLE/source_root"
  du -sh "$BUNDLE"
  # The device tool carries at most 64 MiB. OpenCV's imgcodecs and videoio (linked by the
  # capture and simulator cores) bring GDAL and FFmpeg: ~280 MB, ~96 MB compressed.
  if [ "$(du -sm "$BUNDLE" | cut -f1)" -gt 60 ]; then
    echo "[gpu_check] WARNING: the bundle is over the device tool's 64 MiB carry limit: copy it to" \
         "the GPU machine another way, or run the plain mode there (ROS, nvcc and a GPU)"
  fi
  echo "[gpu_check] bundle ready: $BUNDLE (on the GPU machine: bash scripts/gpu_check.sh --from-bundle $BUNDLE)"
  exit 0
fi

if [ "$MODE" = build ]; then
  build_with_cuda
  BIN_OF() { echo "$ROOT/devel/lib/$1"; }
else
  [ -d "$BUNDLE/bin" ] || { echo "gpu_check: $BUNDLE is not a bundle (--bundle makes one)"; exit 2; }
  export LD_LIBRARY_PATH="$(cd "$BUNDLE" && pwd)/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  # The tests read the package's config files at the paths they were built in: point that
  # path at this copy of the repository.
  src_root="$(cat "$BUNDLE/source_root")"
  if [ "$src_root" != "$ROOT" ] && [ ! -e "$src_root" ]; then
    mkdir -p "$(dirname "$src_root")" && ln -s "$ROOT" "$src_root"
  fi
  BIN_OF() { echo "$BUNDLE/bin/$(basename "$1")"; }
fi

mkdir -p "$OUT"
REPORT="$OUT/report.md"
failures=0
{
  echo "# GPU check $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo
  echo "- git revision: $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)"
  echo "- host: $(hostname), CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ //'), $(nproc) cores"
  if command -v nvidia-smi >/dev/null; then
    echo "- GPU: $(nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm,clocks.max.mem --format=csv,noheader 2>&1 | head -1)"
  else
    echo "- GPU: nvidia-smi not found"
  fi
  echo "- nvcc: $(command -v nvcc >/dev/null && nvcc --version | tail -1 || echo 'not on PATH')"
  echo
} > "$REPORT"

run_logged() {  # name, command...: output into $OUT/<name>.log, a line into the report
  local name="$1"; shift
  local t0=$SECONDS
  "$@" > "$OUT/$name.log" 2>&1
  local rc=$?
  local summary
  summary="$( { grep -E '^\[  (PASSED  |FAILED  |SKIPPED )\] [0-9]+ tests?' "$OUT/$name.log";
                grep -m1 -o 'GPU test skipped: .*' "$OUT/$name.log";
                grep -m1 'ERROR SUMMARY' "$OUT/$name.log"; } | paste -sd ';' -)"
  echo "| $name | $rc | $((SECONDS - t0)) s | ${summary} |" >> "$REPORT"
  [ $rc -eq 0 ] || failures=$((failures + 1))
  echo "[gpu_check] $name: exit $rc ($((SECONDS - t0)) s)"
}

echo "## Tests" >> "$REPORT"
echo >> "$REPORT"
echo "| run | exit | time | gtest / sanitizer summary |" >> "$REPORT"
echo "|---|---:|---:|---|" >> "$REPORT"
SAN="$(command -v compute-sanitizer || ls /usr/local/cuda/bin/compute-sanitizer 2>/dev/null)"
for t in "${GPU_TESTS[@]}"; do
  exe="$(BIN_OF "${t%%:*}")"; filter="*"
  [[ "$t" == *:* ]] && filter="${t#*:}"
  name="$(basename "${t%%:*}")"
  if [ ! -x "$exe" ]; then echo "| $name | - | - | not built |" >> "$REPORT"; failures=$((failures + 1)); continue; fi
  run_logged "$name" "$exe" --gtest_filter="$filter"
  if [ "${SANITIZER:-1}" != 0 ] && [ -n "$SAN" ] && grep -q '^\[  PASSED' "$OUT/$name.log" &&
     ! grep -q 'GPU test skipped' "$OUT/$name.log"; then
    for tool in memcheck racecheck; do
      run_logged "${name}_${tool}" "$SAN" --tool "$tool" --error-exitcode 1 "$exe" --gtest_filter="$filter"
    done
  fi
done

echo >> "$REPORT"
echo "## Benchmarks (GPU beside the CPU path, same run)" >> "$REPORT"
for b in "${GPU_BENCHES[@]}"; do
  exe="$(BIN_OF "$b")"; name="$(basename "$b")"
  echo >> "$REPORT"
  echo "### $name" >> "$REPORT"
  if [ ! -x "$exe" ]; then echo "not built" >> "$REPORT"; failures=$((failures + 1)); continue; fi
  "$exe" > "$OUT/$name.log" 2>&1 || failures=$((failures + 1))
  { echo '```'; cat "$OUT/$name.log"; echo '```'; } >> "$REPORT"
done

echo >> "$REPORT"
echo "failures: $failures" >> "$REPORT"
echo "[gpu_check] report: $REPORT ($failures failures)"
[ $failures -eq 0 ]
