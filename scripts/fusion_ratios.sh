#!/usr/bin/env bash
# Issue 17's ratios on this machine: pSfS fusion against binary SfS of the same frame and round
# (bench_fusion), and the portable face kernel (Highway SSE4, a stand-in for a 128-bit core
# without gathers such as NEON) against the default one. Several rounds, each running every
# benchmark once, so that each ratio comes from one round (the machine's speed may drift between
# rounds); prints the medians with the CPU model and ISA beside the bars. A report, not a test:
# it never fails on a figure. Needs a built workspace (scripts/setup.sh or command 1/2).
#   bash scripts/fusion_ratios.sh [--rounds N] [--simd avx2|scalar] [--out DIR]
# --simd avx2 runs the kernels as on a machine without AVX-512 (TABLETOP_SIMD). Per round ~20 s.
set -eu
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
ROUNDS=5
SIMD=""
OUT=""
while [ $# -gt 0 ]; do
  case "$1" in
    --rounds) ROUNDS="$2"; shift 2 ;;
    --simd) SIMD="$2"; shift 2 ;;
    --out) OUT="$2"; shift 2 ;;
    -h|--help) sed -n '2,10p' "$0"; exit 0 ;;
    *) echo "fusion_ratios: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done
BENCH="$ROOT/devel/lib/psfs_reconstruction/bench_fusion"
if [ ! -x "$BENCH" ]; then
  echo "fusion_ratios: $BENCH not built: run bash scripts/setup.sh first" >&2
  exit 2
fi
OUT="${OUT:-$(mktemp -d /tmp/fusion_ratios_XXXXXX)}"
mkdir -p "$OUT"
FILTER='(BM_PsfsPipelineFrame8?/skin:[01]/below_pct:50/threads:[12]|BM_BinaryPipelineFrame8?/threads:[12]|BM_HandsPipelineFrame/threads:[12]/below_pct:(50/binary:0|0/binary:1)|BM_PsfsFace/threads:1/kernel:[04])/'
for r in $(seq 1 "$ROUNDS"); do
  echo "[fusion_ratios] round $r of $ROUNDS${SIMD:+ (TABLETOP_SIMD=$SIMD)}"
  env ${SIMD:+TABLETOP_SIMD=$SIMD} "$BENCH" --benchmark_filter="$FILTER" --benchmark_min_time=0.3 \
    --benchmark_format=json > "$OUT/round_$r.json" 2> "$OUT/round_$r.log"
done
/usr/bin/python3 - "$OUT" "$ROUNDS" "${SIMD:-default}" <<'EOF'
import json, re, statistics, sys
out, rounds, simd = sys.argv[1], int(sys.argv[2]), sys.argv[3]
model = next((l.split(':', 1)[1].strip() for l in open('/proc/cpuinfo') if l.startswith('model name')), '?')
flags = next((l.split(':', 1)[1].split() for l in open('/proc/cpuinfo') if l.startswith('flags')), [])
isa = 'AVX-512' if 'avx512f' in flags and 'avx512bw' in flags else 'AVX2' if 'avx2' in flags else 'no AVX2'
runs = []
for r in range(1, rounds + 1):
    data = json.load(open(f'{out}/round_{r}.json'))
    runs.append({b['name']: (b['real_time'], b.get('label', '')) for b in data['benchmarks']
                 if b.get('run_type', 'iteration') == 'iteration' and 'error_occurred' not in b})
def ratio(num, den):
    rs = [x[num][0] / x[den][0] for x in runs if num in x and den in x]
    return (statistics.median(rs), min(rs), max(rs)) if rs else None
rows = []
for grid, suffix, bar in (('64x64x48 multi-projection', '', 3.0), ('128x128x96 single projection', '8', 2.0)):
    for kind, skin in (('body', 0), ('skin', 1)):
        for th in (1, 2):
            rows.append((f'{grid}, {kind}, {th} thread(s), vs binary SfS', bar,
                         ratio(f'BM_PsfsPipelineFrame{suffix}/skin:{skin}/below_pct:50/threads:{th}/real_time',
                               f'BM_BinaryPipelineFrame{suffix}/threads:{th}/real_time')))
for th in (1, 2):
    rows.append((f'two hand sub-volumes, {th} thread(s), vs their binary hulls', 3.0,
                 ratio(f'BM_HandsPipelineFrame/threads:{th}/below_pct:50/binary:0/real_time',
                       f'BM_HandsPipelineFrame/threads:{th}/below_pct:0/binary:1/real_time')))
face0 = 'BM_PsfsFace/threads:1/kernel:0/real_time'
label = runs[0].get(face0, (0, '?'))[1]
# The bar is per core against AVX2: on an AVX-512 machine, --simd avx2 gives that figure.
rows.append((f'face kernel, Highway SSE4 vs the default ({label}), 1 thread', 2.0 if 'AVX2' in label else None,
             ratio('BM_PsfsFace/threads:1/kernel:4/real_time', face0)))
print(f'[fusion_ratios] {model}, {isa}, TABLETOP_SIMD={simd}, {rounds} rounds; median (min-max) of per-round ratios')
for name, bar, r in rows:
    if r is None:
        print(f'  {name:74s} not measured')
        continue
    verdict = ('bar against AVX2: run with --simd avx2' if bar is None
               else f'bar {bar:.0f}x: {"met" if r[0] <= bar else "NOT met"}')
    print(f'  {name:74s} {r[0]:5.2f}x ({r[1]:.2f}-{r[2]:.2f})  {verdict}')
print(f'[fusion_ratios] raw results: {out}/round_*.json')
EOF
