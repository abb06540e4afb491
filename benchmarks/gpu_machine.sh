#!/usr/bin/env bash
# The measurements that need the GPU machine (one H100, 16 cores), one stage per `run` call
# (a call may last 10 minutes, a session has 30 minutes of device time, and the machine is
# handed back after 30 s idle, so each stage makes what it needs if it is not there yet).
#
#   bash benchmarks/gpu_wheels.sh .whl                  # on the development machine, once
#   run: bash benchmarks/gpu_machine.sh probe           # what the machine has (no carry needed)
#   run: bash benchmarks/gpu_machine.sh scaling         # carry [".whl"]: issue 14's 16-core figure
#   run: bash benchmarks/gpu_machine.sh learn new       # carry [".whl"]: issue 13, slip traces
#   run: bash benchmarks/gpu_machine.sh learn old       # ... legacy strain-band labels
#   run: bash benchmarks/gpu_machine.sh learn new48     # ... 48 of the 96 train runs (64 vs 128)
#
# Every stage prints JSON lines and appends them to $OUT/gpu_results.jsonl.
#   probe   : Python, torch, CUDA, numba, numpy, scipy versions; CPU model, cores, threads.
#   scaling : `demseis generate` (whole command, start-up included) of 32 `quick` runs on 1
#             worker and 160 on 16 workers, alternated twice; samples/s and the ratio (target
#             >= 13x, 80 % of 16 cores), and the quick preset's store digest (cross-machine bytes).
#   learn L : benchmarks/learnability.py (3000 CUDA steps, base 32) on a 128-run `quick` store
#             with labels L: new = slip traces (default), old = [labels] method = "strain_band",
#             new48 = slip traces trained on 48 of its 96 train runs (the held-out 32 unchanged).
#             The two stores have byte-identical seismic (the labels do not feed the DEM).
#
# GPU_SMALL=1 shrinks every size (2 workers, 8 runs, 20 steps, CPU) to check this script on the
# development machine.
set -euo pipefail
stage=${1:?usage: gpu_machine.sh probe | scaling | learn new|old|new48}
OUT=${OUT:-$PWD/.gpu/out}
WORK=${GPU_WORK:-$PWD/.gpu}
mkdir -p "$OUT" "$WORK"
RESULTS="$OUT/gpu_results.jsonl"

emit() {  # one JSON line to stdout and the results file
    echo "$1" | tee -a "$RESULTS"
}

setup() {  # the carried wheels into .deps (once per machine), on PYTHONPATH with the checkout
    if [ -d .whl ] && [ ! -d .deps ]; then
        python -m pip install --quiet --no-index --no-deps --target .deps .whl/*.whl
    fi
    export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}"
    [ -d .deps ] && export PYTHONPATH="$PYTHONPATH:$PWD/.deps"
    export MPLBACKEND=Agg
    python -c "import demseis, zarr, distributed" \
        || { echo "demseis cannot be imported: carry the wheels (bash benchmarks/gpu_wheels.sh)" >&2; exit 2; }
}

if [ "${GPU_SMALL:-0}" = 1 ]; then
    W_MANY=2; RUNS_ONE=2; RUNS_MANY=4; RUNS_LEARN=8; STEPS=20; HALF=2; DEV=--device=cpu
else
    W_MANY=16; RUNS_ONE=32; RUNS_MANY=160; RUNS_LEARN=128; STEPS=3000; HALF=48; DEV=
fi

timed_generate() {  # WORKERS RUNS OUT MODE [TOML lines...]: whole-command wall seconds on stdout
    # MODE: --overwrite (a fresh store) or --resume (finish or keep an existing one)
    local workers=$1 runs=$2 out=$3 mode=$4; shift 4
    local cfg="$WORK/c_${runs}_$$.toml"
    printf '[sweep]\nn_runs = %s\n' "$runs" > "$cfg"
    for line in "$@"; do printf '%s\n' "$line" >> "$cfg"; done
    local t0 t1
    t0=$(date +%s.%N)
    if [ "$mode" = --overwrite ]; then
        python -m demseis generate "$cfg" --out "$out" --workers "$workers" --overwrite --quiet >&2
    else
        python -m demseis generate "$cfg" --out "$out" --workers "$workers" --quiet >&2
    fi
    t1=$(date +%s.%N)
    python -c "print(round($t1 - $t0, 3))"
}

case "$stage" in
probe)
    python - <<'EOF' | while read -r line; do emit "$line"; done
import json, os, platform, subprocess
info = {"stage": "probe", "python": platform.python_version(), "cpus": os.cpu_count()}
for mod in ("torch", "numba", "numpy", "scipy", "zarr", "distributed", "numcodecs"):
    try:
        info[mod] = __import__(mod).__version__
    except Exception as exc:  # noqa: BLE001
        info[mod] = f"missing ({type(exc).__name__})"
try:
    import torch
    info["cuda"] = torch.cuda.is_available()
    info["gpu"] = torch.cuda.get_device_name(0) if info["cuda"] else None
except Exception:  # noqa: BLE001
    pass
lscpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
for key in ("Model name", "Thread(s) per core", "Core(s) per socket", "Socket(s)"):
    for row in lscpu.splitlines():
        if row.startswith(key + ":"):
            info[key] = row.split(":", 1)[1].strip()
print(json.dumps(info))
EOF
    ;;
scaling)
    setup
    for round in 1 2; do
        for case_ in "1 $RUNS_ONE" "$W_MANY $RUNS_MANY"; do
            set -- $case_
            s=$(timed_generate "$1" "$2" "$WORK/scale_w$1.zarr" --overwrite)
            emit "{\"stage\": \"scaling\", \"round\": $round, \"workers\": $1, \"runs\": $2, \"samples\": $(( $2 * 12 )), \"wall_s\": $s, \"samples_per_s\": $(python -c "print(round($2 * 12 / $s, 3))")}"
            rm -rf "$WORK/scale_w$1.zarr"
        done
    done
    python - "$RESULTS" <<'EOF' | while read -r line; do emit "$line"; done
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if '"stage": "scaling"' in l]
rate = {}
for r in rows:
    rate.setdefault(r["workers"], []).append(r["samples_per_s"])
(one, many) = sorted(rate)
m1, mn = statistics.median(rate[one]), statistics.median(rate[many])
print(json.dumps({"stage": "scaling_summary", "workers": many, "one_worker_samples_per_s": m1,
                  "many_workers_samples_per_s": mn, "speedup": round(mn / m1, 3),
                  "efficiency": round(mn / m1 / many, 3)}))
EOF
    # the quick preset's bytes on this CPU (compare with the development machine's digest)
    python -m demseis generate --preset quick --out "$WORK/digest.zarr" --workers 4 --overwrite --quiet >&2
    emit "$(python benchmarks/store_digest.py "$WORK/digest.zarr")"
    ;;
learn)
    labels=${2:?usage: gpu_machine.sh learn new|old|new48}
    setup
    case "$labels" in
        new|new48) store="$WORK/q${RUNS_LEARN}_new.zarr"; extra=() ;;
        old) store="$WORK/q${RUNS_LEARN}_old.zarr"; extra=('[labels]' 'method = "strain_band"') ;;
        *) echo "learn: new, old or new48, not $labels" >&2; exit 2 ;;
    esac
    # made, finished or (already complete) left as it is: the same seed gives the same seismic
    s=$(timed_generate "$W_MANY" "$RUNS_LEARN" "$store" --resume "${extra[@]}")
    emit "{\"stage\": \"learn_store\", \"labels\": \"$labels\", \"runs\": $RUNS_LEARN, \"wall_s\": $s}"
    # a few held-out sections and predictions come back for benchmarks/learnability_figure.py
    # no bar: the device tool returns only the last 12,000 characters of the output
    args=("$store" --steps "$STEPS" --seed 0 --save-pred "$OUT/pred_$labels.npz" --no-progress)
    [ "$labels" = new48 ] && args+=(--train-runs "$HALF")
    [ -n "$DEV" ] && args+=("$DEV")
    line=$(python benchmarks/learnability.py "${args[@]}" | tail -1)
    emit "{\"stage\": \"learn\", \"labels\": \"$labels\", \"result\": $line}"
    ;;
*)
    echo "unknown stage $stage: probe, scaling or learn" >&2
    exit 2
    ;;
esac
