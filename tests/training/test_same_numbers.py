"""Changes made for speed alone train the same numbers, bit for bit.

Two checks on a short Go1 training under MuJoCo Playground's recipe (``mlp``: randomised
models, uniform observation noise, the command process) and under ``omni`` (``cpg-actor``):

* the code as it is against the reference paths its speed-ups replaced (each kept here as it
  was), in the same process: any machine;
* a digest of the run (parameters, optimiser and normaliser state, the last rollout, the envs'
  state and the episode log) against the one recorded when these paths were last changed:
  a change anywhere that alters what is trained fails it. Bits differ between CPUs, builds
  and library versions, so it runs only where the recording's platform is met (the platform
  line below) and skips elsewhere, naming what differs.
"""

from __future__ import annotations

import dataclasses
import hashlib
import platform

import mujoco
import numpy as np
import pytest
import torch

from cpg_actor.config import compose_config
from cpg_actor.robots.common.actuator import Actuator
from cpg_actor.robots.common.perturbation import Randomization
from cpg_actor.robots.common.quadruped import vector
from cpg_actor.robots.common.quadruped.vector import (
    QuadrupedVectorEnv,
    floor_feet_only,
    model_terms,
)
from cpg_actor.robots.go1.config import Go1Config
from cpg_actor.robots.go1.vector import Go1VectorEnv
from cpg_actor.tasks import velocity as task
from cpg_actor.training.runner import Runner

CASES = {"playground/mlp": ("playground", "mlp"), "omni/cpg-actor": ("omni", "cpg-actor")}

# the digests of run(case), and the platform they were recorded on (platform())
RECORDED_ON = {
    "machine": "x86_64",
    "torch": "2.13.0+cpu",
    "torch_cpu": "AVX512",
    "numpy": "2.4.6",
    "numpy_simd": "AVX512_SPR",
    "mujoco": "4.0.1",
}
DIGESTS = {
    "playground/mlp": "963a3b0cab0d620a",
    "omni/cpg-actor": "661ad5a0a2e6bc9c",
}


# -- the reference paths ---------------------------------------------------------------------
def compiled_afresh(quadruped, config, torque_control: bool = False) -> mujoco.MjModel:
    """``vector.load_model`` as it was before its compiled models were kept: the MJCF
    generated and compiled for every model, the payload's constants in a new MjData."""
    perturbation = config.perturbation
    actuator = None if torque_control else perturbation.actuator(Actuator.from_config(config))
    text = quadruped.mjcf_text(actuator, torque_control=torque_control)
    model = mujoco.MjModel.from_xml_string(text)
    model.opt.timestep = config.physics_dt
    friction = perturbation.ground_friction(config.foot_friction)
    for leg in quadruped.legs:
        model.geom_friction[model.geom(f"{leg}_foot").id, 0] = friction
    model.geom_friction[model.geom("ground").id, 0] = friction
    if config.feet_only:
        floor_feet_only(model, quadruped.legs)
    if perturbation.payload:
        model.body_mass[model.body(quadruped.base_body).id] += perturbation.payload
        mujoco.mj_setConst(model, mujoco.MjData(model))
    if not perturbation.model_nominal:
        model_terms(model, quadruped, perturbation)
    return model


def recipe_noise_per_row(self, obs, index=None):
    """``QuadrupedVectorEnv._recipe_noise`` as it was: each row's draws and arithmetic apart."""
    if not self._noise.any():
        return obs
    rows = range(self.num_envs) if index is None else np.atleast_1d(index)
    width = len(self._noise)
    for i in rows:
        draws = self._rngs[i].uniform(-1.0, 1.0, width)
        obs[i, :width] += task.uniform_noise(draws, self._noise).astype(obs.dtype)
    return obs


def reference_paths(monkeypatch) -> None:
    monkeypatch.setattr(vector, "load_model", compiled_afresh)
    monkeypatch.setattr(QuadrupedVectorEnv, "_recipe_noise", recipe_noise_per_row)


# -- the run -----------------------------------------------------------------------------------
def config(case: str):
    preset, agent = CASES[case]
    values = {"robot": "go1", "agent": agent, "eval_interval": 0, "num_envs": 4, "seed": 7}
    # short episodes: several end (falls and time limits), new ones draw their models
    overrides = ["ppo.num_steps=8", "ppo.compile=false", "env.episode_seconds=0.2",
                 "total_steps=96"]  # fmt: skip
    return compose_config(preset, None, values, overrides)


def feed(digest, value) -> None:
    """Every number of ``value`` (nested dicts, lists, tensors, arrays, plain values) into
    ``digest``, with its structure."""
    if isinstance(value, dict):
        for key in value:
            digest.update(repr(key).encode())
            feed(digest, value[key])
    elif isinstance(value, list | tuple):
        digest.update(f"[{len(value)}".encode())
        for item in value:
            feed(digest, item)
    elif isinstance(value, torch.Tensor):
        feed(digest, value.detach().cpu().numpy())
    elif isinstance(value, np.ndarray):
        digest.update(f"{value.dtype}{value.shape}".encode())
        digest.update(np.ascontiguousarray(value).tobytes())
    else:
        digest.update(repr(value).encode())


def run(case: str) -> dict:
    """What a short training leaves: its numbers, by part."""
    runner = Runner(config(case), run_dir=None, tensorboard=False)
    try:
        runner.learn()
        storage = runner.storage
        return {
            "parameters": runner.agent.state_dict(),
            "optimiser": runner.ppo.optimizer.state_dict()["state"],
            "normaliser": runner.normalizer.state_dict(),
            "storage": {
                name: getattr(storage, name) for name in (*storage.FIELDS, "advantages", "returns")
            },  # fmt: skip
            "obs": runner.rollout.obs,
            "env": runner.env.get_state(),
            "episodes": {
                key: list(values) for key, values in sorted(runner.rollout.episodes.recent.items())
            },  # fmt: skip
            "last_row": {
                k: v
                for k, v in sorted(runner.last_row.items())
                if not k.startswith("time/") and "SPS" not in k
            },  # fmt: skip
        }
    finally:
        runner.close()


def digests(numbers: dict) -> dict[str, str]:
    parts = {}
    for name, value in numbers.items():
        digest = hashlib.sha256()
        feed(digest, value)
        parts[name] = digest.hexdigest()[:16]
    whole = hashlib.sha256("".join(parts.values()).encode()).hexdigest()[:16]
    return {"whole": whole, **parts}


def platform_now() -> dict[str, str]:
    simd = [name for name, on in np._core._multiarray_umath.__cpu_features__.items() if on]
    best = next((f for f in ("AVX512_SPR", "AVX512_ICL", "AVX512_SKX", "AVX2") if f in simd), "")
    return {
        "machine": platform.machine(),
        "torch": torch.__version__,
        "torch_cpu": torch.backends.cpu.get_cpu_capability(),
        "numpy": np.__version__,
        "numpy_simd": best,
        "mujoco": mujoco.__version__,
    }


def same_model(a, b) -> None:
    """Every array and option of two MjModels equal, bit for bit."""
    arrays = [n for n in dir(a) if isinstance(getattr(a, n), np.ndarray)]
    assert "body_mass" in arrays and "dof_invweight0" in arrays
    for name in arrays:
        assert getattr(a, name).tobytes() == getattr(b, name).tobytes(), name
    for struct in ("opt", "stat"):
        for name in dir(getattr(a, struct)):
            value = getattr(getattr(a, struct), name)
            if not name.startswith("_") and isinstance(value, float | int | np.ndarray):
                assert np.array_equal(value, getattr(getattr(b, struct), name)), (struct, name)


@pytest.mark.parametrize("recipe", ["playground", "field"])
def test_an_episodes_model_is_the_one_compiled_afresh(recipe):
    # every number of a randomised episode's model as compiling its MJCF afresh gives,
    # payload constants included, whatever came before: the playground recipe's draws, and
    # every term's (other actuators too)
    base = Go1Config.PLAYGROUND if recipe == "playground" else {
        "randomize": {"preset": "field"}, "floor_contacts": "feet"}  # fmt: skip
    config = Go1Config(**base).validate()
    quadruped = Go1VectorEnv.quadruped
    rng = np.random.default_rng(3)
    for _ in range(6):
        episode = config.randomize.draw(rng, config.decimation, config.perturbation)
        episode_config = dataclasses.replace(config, perturbation=episode,
                                             randomize=Randomization())  # fmt: skip
        same_model(vector.load_model(quadruped, episode_config),
                   compiled_afresh(quadruped, episode_config))  # fmt: skip


@pytest.mark.parametrize("case", list(CASES))
def test_the_speed_ups_train_what_the_reference_paths_train(case, monkeypatch):
    fast = digests(run(case))
    with monkeypatch.context() as patched:
        reference_paths(patched)
        reference = digests(run(case))
    assert fast == reference


@pytest.mark.parametrize("case", list(CASES))
def test_a_short_run_trains_the_recorded_numbers(case):
    now = platform_now()
    differs = {k: (v, now[k]) for k, v in RECORDED_ON.items() if now[k] != v}
    if differs:
        pytest.skip(f"recorded on another platform: {differs} (recorded, here)")
    got = digests(run(case))["whole"]
    assert got == DIGESTS[case], (
        f"{case}: the short run's numbers changed (digest {got}, recorded {DIGESTS[case]}). "
        "A change for speed alone must train the same bits; a change meant to alter "
        "training records its new digest here and says so."
    )
