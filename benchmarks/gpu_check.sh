#!/usr/bin/env bash
# One call on a lent GPU machine (docs/gpu.md, "Measuring on a GPU"): the CUDA tests, the MJX
# throughput table, and a `--preset gpu` training run, everything written under $OUT (at most
# 8 files). The machine's image holds CUDA PyTorch and JAX; mujoco, mujoco-mjx, gymnasium and
# the project's other missing packages travel as wheels in .whl/ (installed to /tmp/site).
# Time limits (seconds) keep the call inside a 10-minute device command.
set -o pipefail
OUT="${OUT:-gpu-check}"
mkdir -p "$OUT"
export PYTHONUNBUFFERED=1 PYTHONPATH="$PWD/src:/tmp/site${PYTHONPATH:+:$PYTHONPATH}"
if compgen -G ".whl/*.whl" >/dev/null; then
    python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
        --target /tmp/site .whl/*.whl || exit 1
fi
{ nvidia-smi -L; python3 -c "import jax, torch; print(jax.devices(), torch.cuda.get_device_name())"; } \
    2>&1 | tee "$OUT/device.txt"
timeout "${TESTS_S:-150}" python3 -m pytest -q -p no:cacheprovider tests/envs/test_mjx.py \
    tests/ppo/test_mjx_training.py tests/test_device.py 2>&1 | tee "$OUT/cuda_tests.txt"
timeout "${BENCH_S:-240}" python3 benchmarks/gpu_throughput.py --envs ${ENVS:-1024 4096 32768 131072} \
    --iterations 2 --output "$OUT/gpu_throughput.md" 2>&1 | tee "$OUT/benchmark.log"
# learning at 4,096 envs: as far as the time allows (metrics.jsonl has the evaluation curve)
timeout "${TRAIN_S:-150}" python3 -m cpg_actor.cli train --preset gpu --total-steps 20M \
    --run-dir /tmp/gpu-run --no-progress --progress-interval 10 2>&1 | tee "$OUT/train.log"
cp /tmp/gpu-run/metrics.jsonl /tmp/gpu-run/config.yaml "$OUT/" 2>/dev/null
exit 0
