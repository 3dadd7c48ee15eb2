#!/usr/bin/env bash
# One call on a lent GPU machine (docs/gpu.md, "Measuring on a GPU"): the CUDA tests, the MJX
# throughput table, a `--preset gpu` training run, (the machine having 16 cores) the CPU
# scaling table of benchmarks/train_scaling.py, and, when PARTS names it, the combined rate of
# runs sharing the GPU (benchmarks/shared_device.py) and a training run with MuJoCo on the CPU
# and PPO on CUDA, and the quadruped's training run and throughput (with many seeds in one
# process); at most 8 files, all under $OUT: cuda_tests.txt (device, then the tests),
# train.log (the trainings' output and configs), metrics.jsonl, metrics_mujoco_cuda.jsonl or
# qtrain.jsonl, gpu_throughput.md, train_scaling.md or go1_throughput.md, shared_device.md,
# and bench.log (the benchmarks' output).
# The machine's image holds CUDA PyTorch and JAX; mujoco, mujoco-mjx, gymnasium and the
# project's other missing packages travel as wheels in .whl/ (installed to /tmp/site).
# Each part has a time limit (seconds) and writes as it goes: a part cut short keeps its output.
# PARTS picks the parts to run, in this order: tests bench train split scaling eval qtrain
# qbench qcontacts share (default: tests bench train scaling; the others run only when named),
# e.g. PARTS="qtrain qbench qcontacts" for the quadruped alone.
set -o pipefail
OUT="${OUT:-gpu-check}"
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1 PYTHONPATH="$PWD/src:/tmp/site${PYTHONPATH:+:$PYTHONPATH}"
# compiled XLA programs shared by the processes below (the same env at the same size)
export JAX_COMPILATION_CACHE_DIR=/tmp/jax-cache JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS=0
if compgen -G ".whl/*.whl" >/dev/null; then
    python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
        --target /tmp/site .whl/*.whl || exit 1
fi
# fails fast (and stops here) if the simulator or CUDA is missing
{ nvidia-smi -L; nproc; python3 - <<'EOF'
import jax, torch
from cpg_actor.robots.hopper.vector import make_vector_env
env = make_vector_env(4, sim="mjx")
obs, _ = env.reset_tensors(seed=0)
print(jax.devices(), jax.__version__, torch.__version__, torch.cuda.get_device_name(), obs.device)
EOF
} 2>&1 | tee "$OUT/cuda_tests.txt" || exit 2
PARTS=" ${PARTS:-tests bench train scaling} "
part() { [[ "$PARTS" == *" $1 "* ]]; }
part tests && timeout "${TESTS_S:-120}" python3 -m pytest -q -p no:cacheprovider tests/test_device.py \
    tests/training/test_mjx_training.py tests/robots/hopper/test_mjx.py \
    tests/robots/anymal/test_anymal_mjx.py tests/robots/go1/test_go1_mjx.py \
    2>&1 | tee -a "$OUT/cuda_tests.txt"
part bench && timeout "${BENCH_S:-170}" python3 benchmarks/gpu_throughput.py \
    --envs ${ENVS:-1024 4096 32768 131072} --agents ${AGENTS:-cpg-actor mlp} --iterations 2 \
    --output "$OUT/gpu_throughput.md" 2>&1 | tee -a "$OUT/bench.log"
# learning at 4,096 envs: as far as the time allows (metrics.jsonl has the evaluation curve)
part train && timeout "${TRAIN_S:-140}" python3 -m cpg_actor.cli train --preset gpu --total-steps 20M \
    --run-dir /tmp/gpu-run --no-progress --progress-interval 10 2>&1 | tee -a "$OUT/train.log"
part train && cat /tmp/gpu-run/config.yaml >>"$OUT/train.log" && cp /tmp/gpu-run/metrics.jsonl "$OUT/"
# the same with MuJoCo's C simulator on the CPU cores and PPO on CUDA: is the GPU run's weaker
# learning torch's on CUDA or MJX's (docs/gpu.md, "Learning")? Its training return at
# iterations 21 and 42 against the train part's and the CPU runs' of docs/results/gpu-preset-mujoco-4096
part split && timeout "${SPLIT_S:-140}" python3 -m cpg_actor.cli train --preset gpu --sim mujoco \
    --device cuda --total-steps 20M --run-dir /tmp/gpu-run-mujoco --no-progress \
    --progress-interval 10 2>&1 | tee -a "$OUT/train.log"
part split && cat /tmp/gpu-run-mujoco/config.yaml >>"$OUT/train.log" \
    && cp /tmp/gpu-run-mujoco/metrics.jsonl "$OUT/metrics_mujoco_cuda.jsonl"
# about a minute per row (a subprocess that compiles): 6 rows need SCALING_S of 400 or so;
# SCALING_ENVS="64 256 1024" adds the throughput preset's own 256 envs (the 2-core 50 % target)
part scaling && timeout "${SCALING_S:-80}" python3 benchmarks/train_scaling.py --cores 2 8 all \
    --num-envs ${SCALING_ENVS:-64 1024} --output "$OUT/train_scaling.md" 2>&1 | tee -a "$OUT/bench.log"
# the evaluation during training on the device against the numpy loop it replaced (docs/gpu.md,
# "Train"): its table goes to bench.log
part eval && timeout "${EVAL_S:-150}" python3 benchmarks/mjx_eval.py --rounds 3 \
    --output /tmp/mjx_eval.md 2>&1 | tee -a "$OUT/bench.log"
# the quadruped (Go1; QROBOT=anymal for ANYmal B): a `--preset gpu` training run as far as the
# time allows (qtrain.jsonl: its metrics, the evaluations' speed error every 10 iterations),
# then its MJX throughput per batch size with QSEEDS seeds in one process (go1_throughput.md)
part qtrain && timeout "${QTRAIN_S:-200}" python3 -m cpg_actor.cli train --preset gpu \
    --robot "${QROBOT:-go1}" --total-steps 50M --run-dir /tmp/gpu-run-quadruped --no-progress \
    --progress-interval 10 2>&1 | tee -a "$OUT/train.log"
part qtrain && cat /tmp/gpu-run-quadruped/config.yaml >>"$OUT/train.log" \
    && cp /tmp/gpu-run-quadruped/metrics.jsonl "$OUT/qtrain.jsonl"
part qbench && timeout "${QBENCH_S:-220}" python3 benchmarks/gpu_throughput.py \
    --robot "${QROBOT:-go1}" --envs ${QENVS:-4096 16384} --agents cpg-actor --iterations 2 \
    --seeds "${QSEEDS:-4}" --output "$OUT/go1_throughput.md" 2>&1 | tee -a "$OUT/bench.log"
# the same rows with every geom touching the floor (env.floor_contacts=all; MJX's default is
# the feet alone): what the feet-only contacts buy on this device (its table to bench.log)
part qcontacts && timeout "${QCONTACTS_S:-150}" python3 benchmarks/gpu_throughput.py \
    --robot "${QROBOT:-go1}" --envs ${QENVS:-4096 16384} --agents cpg-actor --iterations 2 \
    --set env.floor_contacts=all --output /tmp/go1_all_contacts.md 2>&1 | tee -a "$OUT/bench.log"
# runs sharing the GPU: 1, 2 and 4 `--preset gpu` trainings at once (about SHARE_SECONDS each)
part share && timeout "${SHARE_S:-420}" python3 benchmarks/shared_device.py --runs 1 2 4 \
    --seconds "${SHARE_SECONDS:-120}" --output "$OUT/shared_device.md" 2>&1 | tee -a "$OUT/bench.log"
exit 0
