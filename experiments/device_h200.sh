#!/usr/bin/env bash
# Issue 35's figures on a machine with many cores and one GPU, in one call of about 9 minutes:
#
#   OUT=<folder> bash experiments/device_h200.sh            # writes <folder>/device.log and gpu_train_bench.json
#   N_SCALE=4096 N_TRAIN=256 BUDGET_S=10 DEVICE=cpu THREADS="1 2" bash experiments/device_h200.sh   # a smoke run
#
# 1. the machine (CPU, cores, GPU, versions);
# 2. training at machine scale: experiments/gpu_train_bench.py (throughput of `train-fast` on --device, then a
#    generalist trained for BUDGET_S seconds, its validation curve, and it against the analytic controller on the
#    ideal cells; the model comes back as gpu_model.zip); last, with --overlap, the throughput at N_TRAIN again with
#    `train-fast --overlap` (about 30 s; after the budgeted training, whose budget it leaves as it was);
# 3. the vector env's step against numba's threads at N = N_SCALE, the step alone (thread_wait.py's work = 0):
#    AmigoBot-v0 and v1 (defaults) on each of THREADS, v1 on the last also with OMP_WAIT_POLICY=ACTIVE, v0 and v1 on
#    the last also with GOMP_SPINCOUNT=0 (the env's default is PASSIVE with a spin of 1000, before 2026-12-01 PASSIVE
#    alone); v1's training distribution on the first and the last; then the share of v1's one-thread
#    step outside its parallel loop (experiments/serial_share.py: what bounds the threads' speed-up), at N_SCALE with
#    the defaults and at N_TRAIN as train-fast steps it (restarts and the final infos included); last, v0's step on
#    the last THREADS by function (experiments/step_profile.py: what stays on the calling thread).
# Each step has its own time limit, so one that fails or runs long leaves the others their time.
# --overlap at N = 65,536 (where the learner's share is largest), a second call of about 3 minutes if the lease has it:
#   python3 experiments/gpu_train_bench.py --budget-s 1 --n-envs 16384 --sizes 65536 --measure-iters 16 \
#       --curve-points 1 --episodes 1 --device cuda --overlap --json "$OUT/gpu_overlap_sizes.json"
set -u
OUT=${OUT:-/tmp/amigo_device}
N_SCALE=${N_SCALE:-65536} N_TRAIN=${N_TRAIN:-16384} BUDGET_S=${BUDGET_S:-180} DEVICE=${DEVICE:-cuda}
THREADS=${THREADS:-"1 16"}
mkdir -p "$OUT"
export PYTHONPATH=$PWD${PYTHONPATH:+:$PYTHONPATH} PYTHONUNBUFFERED=1
py=${PYTHON:-python3}
last=${THREADS##* } first=${THREADS%% *}
export NUMBA_NUM_THREADS=${NUMBA_NUM_THREADS:-$last}
{
    echo "== machine: $(date -u +%FT%TZ)"
    lscpu | grep -Ei 'model name|thread\(s\)|core\(s\)|socket'
    echo "cpus $(nproc), load $(cut -d' ' -f1-3 /proc/loadavg)"
    nvidia-smi -L 2>/dev/null || echo "no nvidia-smi"
    $py -c "import sys, numpy, numba, torch, gymnasium; print('python', sys.version.split()[0], 'numpy', numpy.__version__,
        'numba', numba.__version__, 'torch', torch.__version__, 'gymnasium', gymnasium.__version__,
        'cuda', torch.cuda.is_available())"
    echo "== training (experiments/gpu_train_bench.py)"
    timeout 480 $py experiments/gpu_train_bench.py --budget-s "$BUDGET_S" --n-envs "$N_TRAIN" --device "$DEVICE" \
        --deadline-s 420 --overlap --json "$OUT/gpu_train_bench.json" || echo "gpu_train_bench: exit $?"
    echo "== threads (experiments/thread_wait.py, work = 0, N = $N_SCALE)"
    for env in AmigoBot-v0 AmigoBot-v1; do
        for t in $THREADS; do
            timeout 60 $py experiments/thread_wait.py $env "$N_SCALE" "$t" 0 || echo "$env $t: exit $?"
        done
    done
    OMP_WAIT_POLICY=ACTIVE timeout 60 $py experiments/thread_wait.py AmigoBot-v1 "$N_SCALE" "$last" 0 || echo "exit $?"
    for env in AmigoBot-v0 AmigoBot-v1; do
        GOMP_SPINCOUNT=0 timeout 60 $py experiments/thread_wait.py $env "$N_SCALE" "$last" 0 || echo "$env spin 0: exit $?"
    done
    for t in $first $last; do
        timeout 90 $py experiments/thread_wait.py AmigoBot-v1 "$N_SCALE" "$t" 0 training || echo "training $t: exit $?"
    done
    timeout 60 $py experiments/serial_share.py "$N_SCALE" || echo "serial_share: exit $?"
    timeout 120 $py experiments/serial_share.py "$N_TRAIN" training || echo "serial_share training: exit $?"
    timeout 60 $py experiments/step_profile.py AmigoBot-v0 "$N_SCALE" numba-parallel 30 10 || echo "profile: exit $?"
    echo "== done: $(date -u +%FT%TZ)"
} 2>&1 | tee "$OUT/device.log"
