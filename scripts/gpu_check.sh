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
# Absolute: the loader is given the bundle's folders, and ldd reports what it found there.
[ -n "$BUNDLE" ] && BUNDLE="$(realpath -m "$BUNDLE")"

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

# stub_library REAL WANTED OUT: a library with REAL's soname that defines the symbols of REAL
# listed in WANTED (functions return at once, objects are zeroed), with REAL's symbol versions.
stub_library() {
  local real="$1" wanted="$2" out="$3" soname tmp line size type name base ver v
  soname="$(readelf -d "$real" | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p')"
  tmp="$(mktemp -d)"
  local -A versions=()
  : > "$tmp/stub.s"
  while read -r line; do
    set -- $line  # value [size] type name[@[@]version]
    if [ $# -eq 4 ]; then size="$2" type="$3" name="$4"; else size=0 type="$2" name="$3"; fi
    base="${name%%@*}"; ver=""
    [[ "$name" == *@* ]] && ver="${name##*@}"
    grep -qxF "$base" "$wanted" || continue
    case "$type" in
      T|t|W|i) printf '.text\n.globl %s\n.type %s,@function\n%s:\n ret\n' "$base" "$base" "$base" ;;
      *) v=$((16#${size:-0})); [ "$v" -gt 0 ] || v=8
         printf '.data\n.globl %s\n.type %s,@object\n.size %s,%d\n%s:\n .zero %d\n' "$base" "$base" "$base" "$v" "$base" "$v" ;;
    esac >> "$tmp/stub.s"
    [ -n "$ver" ] && versions["$ver"]+="$base; "
  done < <(nm -D --defined-only -S "$real" 2>/dev/null)
  local script=()
  if [ ${#versions[@]} -gt 0 ]; then
    for v in "${!versions[@]}"; do printf '%s { global: %s };\n' "$v" "${versions[$v]}"; done > "$tmp/vers"
    script=(-Wl,--version-script="$tmp/vers")
  fi
  gcc -shared -nostdlib -o "$out/$soname" -Wl,-soname,"$soname" "${script[@]}" "$tmp/stub.s"
  rm -rf "$tmp"
}

# OpenCV's imgcodecs and videoio (the capture and simulator cores link them) bring GDAL, GDCM,
# FFmpeg and GStreamer, ~280 MB: more than the device tool carries (64 MiB). The GPU tests
# never call those (the simulator's JPEG artefacts use libjpeg, kept), so they are replaced by
# stubs that only satisfy the loader (OpenCV is linked with BIND_NOW, so every imported symbol
# must resolve at load time), and the libraries nothing needs any more are dropped. Checked by
# loading every executable of the bundle; on any failure the bundle stays untrimmed.
trim_bundle() {
  local lib="$BUNDLE/lib" stubs="$BUNDLE/stubs" keep='^lib(opencv_|jpeg|png16|z\.|stdc\+\+|gcc_s|c\.|m\.|ld-linux)'
  command -v nm >/dev/null && command -v readelf >/dev/null || { echo "[gpu_check] binutils missing: bundle not trimmed"; return; }
  mkdir -p "$stubs"
  local wanted; wanted="$(mktemp)"
  for f in "$lib"/*.so* "$BUNDLE"/bin/*; do nm -D --undefined-only "$f" 2>/dev/null | awk '{print $NF}' | sed 's/@.*//'; done | sort -u > "$wanted"
  local imp dep
  for imp in "$lib"/libopencv_imgcodecs.so.* "$lib"/libopencv_videoio.so.*; do
    [ -f "$imp" ] || continue
    for dep in $(readelf -d "$imp" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'); do
      [[ "$dep" =~ $keep ]] && continue
      [ -f "$stubs/$dep" ] || stub_library "$lib/$dep" "$wanted" "$stubs"
    done
  done
  rm -f "$wanted"
  # What the executables load now, stubs first.
  local needed
  needed="$(for exe in "$BUNDLE"/bin/*; do LD_LIBRARY_PATH="$stubs:$lib" ldd "$exe"; done | awk '/=> \//{print $3}' | sort -u)"
  local ok=1 exe
  for exe in "$BUNDLE"/bin/*; do
    if [[ "$(basename "$exe")" == test_* ]]; then
      LD_LIBRARY_PATH="$stubs:$lib" "$exe" --gtest_list_tests > /dev/null 2>&1 || { ok=0; echo "[gpu_check] trimmed bundle: $(basename "$exe") does not load"; }
    fi
  done
  if [ $ok -eq 0 ]; then rm -rf "$stubs"; echo "[gpu_check] bundle left untrimmed"; return; fi
  local f
  for f in "$lib"/*; do
    grep -qxF "$f" <<< "$needed" || rm -f "$f"
  done
  mv "$stubs"/* "$lib"/ && rmdir "$stubs"
  echo "[gpu_check] bundle trimmed: $(ls "$lib" | wc -l) libraries ($(grep -c "$stubs" <<< "$needed") stubs)"
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
  trim_bundle
  du -sh "$BUNDLE"
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
