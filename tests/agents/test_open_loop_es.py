"""The open-loop search baseline (agent ``open-loop-es``): CMA-ES over the open-loop
CPG-Actor's V. Small budgets: hopper episodes of a few dozen control steps, a few candidates."""

import json
import math
import pickle

import numpy as np
import pytest
import torch

from cpg_actor.agents import get_agent_spec
from cpg_actor.agents.gait_file import load_gait, write_gait
from cpg_actor.agents.open_loop_es import CMASearch, ESConfig, Rollouts, episode_seeds
from cpg_actor.cli import main
from cpg_actor.config import TrainConfig, compose_config
from cpg_actor.deploy import Policy, load_policy
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.registry import get_robot
from cpg_actor.training.build import make_env
from cpg_actor.training.checkpoint import load_checkpoint
from cpg_actor.training.es_runner import ESRunner
from cpg_actor.training.evaluation import evaluate

# tests/ppo/fake_env.py: pytest puts tests/ on sys.path (tests/ is not a package)
from ppo.fake_env import FakeHopperVectorEnv  # noqa: I001

POPSIZE, STEPS = 4, 20  # candidates per generation, control steps per episode
GENERATION = POPSIZE * STEPS  # env steps of one generation (one episode per candidate)
TINY = ["--agent", "open-loop-es", "--set", f"env.episode_steps={STEPS}"]
TINY += ["--set", f"es.popsize={POPSIZE}", "--set", "eval_episodes=2", "--no-progress"]


def es_config(generations: int, **fields) -> TrainConfig:
    fields.setdefault("eval_interval", 0)
    return TrainConfig(
        agent="open-loop-es",
        total_steps=generations * GENERATION,
        env=HopperConfig(episode_steps=STEPS),
        es=ESConfig(popsize=POPSIZE),
        **fields,
    )


def without_timing(row: dict) -> dict:
    return {k: v for k, v in row.items() if not k.startswith("time/") and k != "charts/SPS"}


def metrics(run_dir) -> list[dict]:
    return [json.loads(line) for line in (run_dir / "metrics.jsonl").read_text().splitlines()]


def test_the_search_improves_a_known_objective_through_the_runner():
    """A quadratic in V with its maximum away from the start, injected where the episodes'
    returns go: the runner's ask / evaluate / tell path closes in on it, and the agent keeps
    the best candidate evaluated."""
    runner = ESRunner(es_config(40), tensorboard=False)
    target = runner.start_vector.double().numpy() + np.linspace(-0.5, 0.5, runner.vector.numel())

    def quadratic(candidates):
        returns = -np.sum((candidates - target) ** 2, axis=1)
        return Rollouts(returns[:, None], np.full((POPSIZE, 1), STEPS), {}, {}, GENERATION)

    runner.evaluate_candidates = quadratic
    try:
        start = -float(np.sum((runner.start_vector.double().numpy() - target) ** 2))
        runner.learn()
    finally:
        runner.close()
    assert runner.iteration == 40 and runner.global_step == 40 * GENERATION
    assert runner.search.best_fitness > 0.05 * start  # within 5 % of the start's distance
    kept = runner.vector.detach().double().numpy()
    assert runner.search.best_fitness == pytest.approx(-np.sum((kept - target) ** 2), rel=1e-5)
    assert np.array_equal(runner.vector.detach().numpy(), runner.search.best_x.astype(np.float32))


def test_cma_search_finds_a_quadratic_optimum_and_its_state_continues_exactly():
    search = CMASearch(np.zeros(5), 0.3, 8, seed=1)
    target = np.array([1.0, -0.5, 0.2, 0.0, 0.7])
    for _ in range(60):
        candidates = search.ask()
        search.tell(candidates, -np.sum((candidates - target) ** 2, axis=1))
    assert np.allclose(search.best_x, target, atol=1e-2)
    copy = CMASearch(np.zeros(5), 0.3, 8, seed=2)
    copy.load_state_dict(search.state_dict())
    assert np.array_equal(copy.ask(), search.ask())  # the same generator state
    assert np.array_equal(copy.mean, search.mean) and copy.sigma == search.sigma


def _with_bytes(state: dict, data: bytes) -> dict:
    return {**state, "cma": torch.frombuffer(bytearray(data), dtype=torch.uint8)}


def _text(text: str) -> bytes:
    raw = text.encode()
    return pickle.SHORT_BINUNICODE + bytes([len(raw)]) + raw


def _global(module: str, name: str) -> bytes:
    """Protocol-4 opcodes that push ``module.name`` (the unpickler follows a dotted name)."""
    return _text(module) + _text(name) + pickle.STACK_GLOBAL


def _call(module: str, name: str, *args: str) -> bytes:
    """A pickle that calls ``module.name(*args)`` (REDUCE)."""
    arguments = pickle.MARK + b"".join(_text(a) for a in args) + pickle.TUPLE
    return pickle.PROTO + b"\x04" + _global(module, name) + arguments + pickle.REDUCE + pickle.STOP


def _logger_payload(marker: str) -> bytes:
    """cma's data logger made with NEWOBJ, its file names set by BUILD, then its ``add()``
    called by ADDITEMS: the opcodes of the reported payload that wrote a file where the pickle
    said (a ``.pth`` in site-packages runs code at every Python start)."""
    logger = _global("cma.logger", "CMADataLogger") + pickle.EMPTY_TUPLE + pickle.NEWOBJ
    fields = pickle.EMPTY_DICT + pickle.MARK
    fields += _text("name_prefix") + _text(marker) + _text("file_parameters") + _text(".pth")
    fields += pickle.SETITEMS
    return (
        pickle.PROTO + b"\x04" + logger + fields + pickle.BUILD
        + pickle.MARK + _text("import os") + pickle.ADDITEMS + pickle.STOP
    )  # fmt: skip


def _randomstate_payload(marker: str) -> bytes:
    """numpy's ``__randomstate_ctor(arg, f)`` calls ``f(arg)``: here ``print``."""
    return _call("numpy.random._pickle", "__randomstate_ctor", marker)


CRAFTED = {
    # the payload that ran a command: cma + a dotted name reaching subprocess.Popen via numpy
    "popen": lambda marker: _call("cma", "_np.f2py.subprocess.Popen", "touch", marker),
    "memmap": lambda marker: _call("numpy", "memmap", marker, "uint8", "w+"),
    "print": lambda marker: _call("builtins", "print", marker),
    # a listed class's constructor: cma's creates log files where its options say
    "cma-constructor": lambda marker: _call(
        "cma.evolution_strategy", "CMAEvolutionStrategy", marker
    ),
    "cma-logger": _logger_payload,
    "numpy-randomstate-ctor": _randomstate_payload,
    # BUILD on a listed class itself would patch that class for the whole process
    "build-class": lambda marker: pickle.PROTO + b"\x04"
    + _global("cma.evolution_strategy", "CMAEvolutionStrategy")
    + pickle.NONE + pickle.MARK + _text("__setstate__") + _text(marker) + pickle.DICT
    + pickle.TUPLE2 + pickle.BUILD + pickle.STOP,
}  # fmt: skip


@pytest.mark.parametrize("payload", sorted(CRAFTED))
def test_a_pickled_search_state_is_never_read(payload, tmp_path, monkeypatch):
    """A checkpoint whose CMA-ES state is pickle bytes (the older format, or a crafted file):
    refused in one line before anything reads it; nothing runs, nothing is written."""
    import cma

    monkeypatch.chdir(tmp_path)
    marker = tmp_path / "ran"
    search = CMASearch(np.zeros(3), 0.3, 4, seed=0)
    state = _with_bytes(search.state_dict(), CRAFTED[payload](str(marker)))
    with pytest.raises(ValueError, match="CMA-ES state is a pickle") as error:
        search.load_state_dict(state)
    assert "\n" not in str(error.value)
    assert list(tmp_path.iterdir()) == []  # nothing ran, nothing was written
    assert "__setstate__" not in vars(cma.CMAEvolutionStrategy)


@pytest.mark.parametrize("payload", ["cma-logger", "numpy-randomstate-ctor", "popen"])
def test_a_crafted_open_loop_es_checkpoint_neither_writes_nor_runs(payload, tmp_path, capsys):
    """The whole path a user takes: ``cpg-actor train --resume`` on a downloaded open-loop-es
    run whose checkpoint carries a crafted pickle. One line, exit 2, no file written outside
    what the run itself had."""
    run = tmp_path / "run"
    args = [*TINY, "--total-steps", str(2 * GENERATION), "--set", "checkpoint_interval=1"]
    assert main(["train", "--run-dir", str(run), *args, "--set", "eval_interval=0"]) == 0
    path = run / "checkpoints" / "last.pt"
    data = torch.load(path, weights_only=True)
    marker = tmp_path / "planted"
    data["es"] = _with_bytes(data["es"], CRAFTED[payload](str(marker)))
    torch.save(data, path)
    before = sorted(p for p in tmp_path.rglob("*"))
    capsys.readouterr()
    more = str(3 * GENERATION)
    code = main(
        ["train", "--run-dir", str(run), "--resume", "--total-steps", more, "--no-progress"]
    )
    err = capsys.readouterr().err
    assert code == 2 and "pickle" in err and len(err.strip().splitlines()) == 1, err
    assert sorted(p for p in tmp_path.rglob("*")) == before
    assert not any(tmp_path.parent.glob("*.pth")) and not marker.exists()


def _state_values(value):
    """Every leaf of a saved search state."""
    if isinstance(value, dict):
        for item in value.values():
            yield from _state_values(item)
    elif isinstance(value, list):
        for item in value:
            yield from _state_values(item)
    else:
        yield value


def test_a_search_state_is_tensors_and_plain_numbers_only(tmp_path):
    search = CMASearch(np.zeros(4), 0.3, 4, seed=0)
    for _ in range(5):
        candidates = search.ask()
        search.tell(candidates, -np.sum(candidates**2, axis=1))
    state = search.state_dict()
    kinds = {type(v) for v in _state_values(state)}
    assert kinds <= {torch.Tensor, int, float, bool, type(None)}, kinds
    torch.save(state, tmp_path / "state.pt")
    read = torch.load(tmp_path / "state.pt", weights_only=True)
    copy = CMASearch(np.ones(4), 1.0, 4, seed=3)
    copy.load_state_dict(read)
    assert np.array_equal(copy.ask(), search.ask())


def _numeric_leaves(root, prefix="", seen=None, out=None):
    """Every number, array and list of numbers reachable from a cma object, by path."""
    seen = set() if seen is None else seen
    out = {} if out is None else out
    if id(root) in seen:
        return out
    seen.add(id(root))
    if isinstance(root, dict):
        items = [(str(key), value) for key, value in root.items()]
    elif type(root).__module__.startswith("cma") and hasattr(root, "__dict__"):
        items = list(vars(root).items())
    else:
        return out
    for name, value in items:
        path = prefix + name
        if isinstance(value, (np.ndarray, int, float, np.number, type(None), range)):
            out[path] = value
        elif isinstance(value, (list, tuple)):
            out[path] = [np.asarray(v).tolist() for v in value]
        else:
            _numeric_leaves(value, path + ".", seen, out)
    return out


# what changes in a running search and is not its state: wall-clock timers, the options, a
# cache keyed by constants, the arguments of the last tell kept for debugging, the population
# of a generation (emptied by tell)
NOT_STATE = ("opts.", "inopts.", "adapt_sigma._es_opts.", "_round_integer_variables.params.",
             "timer.", "logger.timer_", "sigma_vec._parameters.", "_tell2_args.",
             "pop")  # fmt: skip


@pytest.mark.parametrize("popsize", [4, 8])  # 4: cma's selective mirrors are on
def test_every_value_a_running_search_changes_is_in_its_saved_state(popsize):
    """A guard for cma versions: whatever a running search changes is listed in
    cma_state.FIELDS (or is a documented non-state), else resume could be inexact."""
    from cpg_actor.agents.cma_state import ALIASES, FIELDS

    def same(a, b):
        if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
            return np.shape(a) == np.shape(b) and np.array_equal(a, b, equal_nan=True)
        return type(a) is type(b) and (a == b or a != a and b != b)

    fresh = _numeric_leaves(CMASearch(np.zeros(3), 0.3, popsize, seed=1).es)
    search = CMASearch(np.zeros(3), 0.3, popsize, seed=1)
    changed = set()
    for _ in range(60):
        candidates = search.ask()
        search.tell(candidates, -np.sum(np.cos(3 * candidates) + candidates**2, axis=1))
        leaves = _numeric_leaves(search.es)
        changed |= {path for path, value in leaves.items() if not same(fresh.get(path), value)}
    unlisted = {
        path for path in changed
        if path not in FIELDS and path not in ALIASES and not path.startswith(NOT_STATE)
    }  # fmt: skip
    assert unlisted == set()


def _rosenbrock(candidates: np.ndarray) -> np.ndarray:
    x = candidates
    return -np.sum(100 * (x[:, 1:] - x[:, :-1] ** 2) ** 2 + (1 - x[:, :-1]) ** 2, axis=1)


@pytest.mark.parametrize(("dimension", "popsize", "cut"), [(5, 8, 0), (5, 8, 7), (3, 4, 40)])
def test_a_restored_search_continues_exactly_to_its_stop(dimension, popsize, cut):
    """Saved after ``cut`` generations and rebuilt in a search made with another start, step
    size and seed: every later generation's candidates, the stopping criteria and the result
    equal the uninterrupted search's, bit for bit, until CMA-ES stops (a NaN fitness now and
    then)."""
    straight = CMASearch(np.zeros(dimension), 0.3, popsize, seed=1)
    for _ in range(cut):
        candidates = straight.ask()
        straight.tell(candidates, _rosenbrock(candidates))
    resumed = CMASearch(np.ones(dimension), 0.9, popsize, seed=5)
    resumed.load_state_dict(straight.state_dict())
    for generation in range(400):
        candidates = straight.ask()
        assert np.array_equal(resumed.ask(), candidates), generation
        fitness = _rosenbrock(candidates)
        if generation % 37 == 5:
            fitness[1] = np.nan
        straight.tell(candidates, fitness)
        resumed.tell(candidates, fitness.copy())
        assert resumed.stop_reason == straight.stop_reason
        if straight.stop_reason:
            break
    assert straight.stop_reason  # it ran to CMA-ES's own end
    assert resumed.best_fitness == straight.best_fitness
    assert np.array_equal(resumed.best_x, straight.best_x)


def _saved_state() -> tuple[CMASearch, dict]:
    search = CMASearch(np.zeros(3), 0.3, 4, seed=0)
    for _ in range(3):
        candidates = search.ask()
        search.tell(candidates, -np.sum(candidates**2, axis=1))
    return search, search.state_dict()


def _edit(state: dict, path: str, value) -> dict:
    edited = {**state, "cma": {**state["cma"]}}
    if path.startswith("randn."):
        edited["cma"]["randn"] = {**state["cma"]["randn"], path[6:]: value}
    elif path in edited["cma"]:
        edited["cma"][path] = value
    else:
        edited[path] = value
    return edited


BAD_STATES = {
    "mean of another size": ("mean", torch.zeros(5, dtype=torch.float64)),
    "covariance as float32": ("sm.C", torch.eye(3)),
    "NaN step size": ("sigma", float("nan")),
    "step size as text": ("sigma", "0.3"),
    "counter as float": ("countiter", 3.0),
    "huge history": ("fit.hist", [0.0] * 200_001),
    "history of strings": ("fit.hist", ["1"]),
    "order not a permutation": ("fit.idx", torch.zeros(4, dtype=torch.int64)),
    "a nested dict": ("pc", {"a": {"b": 1}}),
    "generator keys short": ("randn.keys", torch.zeros(3, dtype=torch.int64)),
    "generator keys out of range": ("randn.keys", torch.full((624,), 2**40)),
    "generator pos out of range": ("randn.pos", 10**6),
    "best_x of another size": ("best_x", torch.zeros(9, dtype=torch.float64)),
    "generation as text": ("generation", "3"),
}


@pytest.mark.parametrize("case", sorted(BAD_STATES))
def test_a_damaged_search_state_is_one_line_and_changes_nothing(case):
    search, state = _saved_state()
    before = search.ask()
    search, state = _saved_state()
    path, value = BAD_STATES[case]
    with pytest.raises(ValueError) as error:
        search.load_state_dict(_edit(state, path, value))
    message = str(error.value)
    assert "\n" not in message and len(message) < 300, message
    assert np.array_equal(search.ask(), before)  # the running search is untouched


@pytest.mark.parametrize("change", ["unknown field", "missing field", "not a dict"])
def test_a_search_state_of_another_shape_is_refused(change):
    search, state = _saved_state()
    cma = dict(state["cma"])
    if change == "unknown field":
        cma["logger.name_prefix"] = 1.0
    elif change == "missing field":
        del cma["sm.C"]
    else:
        cma = [1, 2, 3]
    with pytest.raises(ValueError, match="CMA-ES state") as error:
        search.load_state_dict({**state, "cma": cma})
    assert "\n" not in str(error.value)


def test_non_finite_fitness_ranks_last_and_is_never_kept():
    search = CMASearch(np.zeros(2), 0.3, 4, seed=0)
    candidates = search.ask()
    search.tell(candidates, np.array([math.nan, -1.0, math.inf * -1, -3.0]))
    assert search.best_fitness == -1.0
    assert np.array_equal(search.best_x, candidates[1])


def test_candidates_act_as_the_agent_with_their_vector_acts():
    """The batched (vmapped) rollout of a candidate returns what the agent with that V earns
    in the deterministic evaluation on the same reset seed."""
    runner = ESRunner(es_config(1), tensorboard=False)
    try:
        candidates = runner.search.ask()
        seeds = episode_seeds(0, 0, 1)
        rollouts = runner.rollouts.run(torch.as_tensor(candidates, dtype=torch.float32), seeds)
        env = make_env(runner.config, runner.robot, 1, None)
        try:
            for c in (0, POPSIZE - 1):
                with torch.no_grad():
                    runner.vector.copy_(torch.as_tensor(candidates[c]))
                policy = Policy(
                    runner.agent, runner.normalizer, runner.action_low, runner.action_high
                )
                result = evaluate(policy, env, seeds[0], 0.01, STEPS, traces=False)
                assert rollouts.returns[c, 0] == pytest.approx(
                    result["episode_return"][0], rel=1e-9
                )
                assert rollouts.metrics["hop_height"][c, 0] == result["hop_height"][0]
        finally:
            env.close()
    finally:
        runner.close()
    assert rollouts.env_steps == GENERATION
    assert set(rollouts.reward_terms) == {"r1", "r2", "r3", "r4", "r5"}


def test_a_short_hopper_search_beats_its_starting_gait(tmp_path):
    """Real MuJoCo hopper, 40-step episodes, 6 generations: the best gait found returns more
    than the preset's in the deterministic evaluation (the same seeds before and after)."""
    config = es_config(6, eval_interval=3, eval_episodes=2, seed=3)
    config.env.episode_steps, config.total_steps = 40, 6 * POPSIZE * 40
    runner = ESRunner(config, tmp_path, tensorboard=False)
    try:
        runner.learn()
    finally:
        runner.close()
    rows = metrics(tmp_path)
    assert [row["iteration"] for row in rows] == list(range(7))
    start, end = rows[0]["eval/return"], rows[-1]["eval/return"]
    assert end > start + 1.0, (start, end)
    best = [row["es/best_return"] for row in rows[1:]]
    assert best == sorted(best)  # the best so far never falls
    assert best[-1] > rows[1]["es/mean_return"]
    for key in ("es/mean_return", "es/sigma", "charts/hop_height", "cpg/nu_HFE", "cpg/w_HFE_KFE"):
        assert key in rows[-1], key
    assert not any(key.startswith("policy/") for key in rows[-1])  # the unused Gaussian std


def test_interrupted_and_resumed_search_equals_the_straight_one(tmp_path, capsys, monkeypatch):
    """Interrupted at generation 4 (checkpoint at 2), resumed: V, the CMA-ES state, the gait
    and every metric but timings equal the uninterrupted run's, bit for bit."""
    straight, split = tmp_path / "straight", tmp_path / "split"
    args = [*TINY, "--total-steps", str(5 * GENERATION), "--set", "checkpoint_interval=2"]
    args += ["--set", "eval_interval=2"]
    assert main(["train", "--run-dir", str(straight), *args]) == 0

    generation = ESRunner.generation

    def interrupted(self):
        if self.iteration == 3:
            raise KeyboardInterrupt
        return generation(self)

    monkeypatch.setattr(ESRunner, "generation", interrupted)
    assert main(["train", "--run-dir", str(split), *args]) == 130
    assert "--resume" in capsys.readouterr().err
    assert len(metrics(split)) == 4  # generations 0 (the start's evaluation) to 3
    monkeypatch.setattr(ESRunner, "generation", generation)
    assert main(["train", "--run-dir", str(split), "--resume", "--no-progress"]) == 0
    assert "resuming" in capsys.readouterr().out

    a = load_checkpoint(straight / "checkpoints" / "last.pt")
    b = load_checkpoint(split / "checkpoints" / "last.pt")
    assert a["iteration"] == b["iteration"] == 5
    assert a["global_step"] == b["global_step"] == 5 * GENERATION
    for key, value in a["agent_state"].items():
        assert torch.equal(value, b["agent_state"][key]), key
    searches = []
    for data in (a, b):
        search = CMASearch(np.zeros(8), 1.0, POPSIZE, seed=0)
        search.load_state_dict(data["es"])
        searches.append(search)
    assert np.array_equal(searches[0].mean, searches[1].mean)
    assert searches[0].sigma == searches[1].sigma
    assert np.array_equal(searches[0].es.C, searches[1].es.C)
    assert np.array_equal(searches[0].ask(), searches[1].ask())
    assert searches[0].best_fitness == searches[1].best_fitness
    rows_a, rows_b = metrics(straight), metrics(split)
    assert [row["iteration"] for row in rows_b] == list(range(6))
    assert [without_timing(r) for r in rows_a] == [without_timing(r) for r in rows_b]
    assert load_gait(straight) == load_gait(split)
    # generation 3, logged before the interruption and again after the resume: once in
    # TensorBoard (the resumed writer purges what came after the checkpoint)
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    events = EventAccumulator(str(split / "tensorboard"), size_guidance={"scalars": 0})
    events.Reload()
    steps = [event.step for event in events.Scalars("es/best_return")]
    assert steps == [row["global_step"] for row in rows_b[1:]]


def test_steps_are_counted_and_the_budget_is_never_exceeded(tmp_path, capsys):
    total = 3 * GENERATION + GENERATION // 2  # three and a half generations
    run = tmp_path / "run"
    assert main(["train", "--run-dir", str(run), *TINY, "--total-steps", str(total)]) == 0
    out = capsys.readouterr().out
    assert "not a whole number of generations" in out and f"{3 * GENERATION:,}" in out
    rows = metrics(run)
    assert [row["global_step"] for row in rows] == [0, *(g * GENERATION for g in (1, 2, 3))]
    assert load_gait(run)["steps_searched"] == 3 * GENERATION <= total

    # a budget below one generation is refused, naming what a generation costs
    code = main(["train", "--run-dir", str(tmp_path / "x"), *TINY, "--total-steps", "50"])
    assert code == 2
    assert f"= {GENERATION} steps" in capsys.readouterr().err


def test_episodes_that_end_early_count_every_env_step_the_search_took():
    """On a stand-in env whose robots fall at random, a generation costs sub-envs x the
    steps until its last episode ended; the episodes' lengths are their own."""
    config = es_config(4)
    config.env.episode_steps = 15
    config.total_steps = 4 * POPSIZE * 15
    fake = FakeHopperVectorEnv(POPSIZE)
    fake.config.fall_probability = 0.3
    runner = ESRunner(config, env=fake, tensorboard=False)
    counted = []
    generation = runner.evaluate_candidates

    def spy(candidates):
        rollouts = generation(candidates)
        counted.append((rollouts.env_steps, rollouts.lengths.copy()))
        return rollouts

    runner.evaluate_candidates = spy
    try:
        runner.learn()
    finally:
        runner.close()
    assert runner.iteration == 4
    assert runner.global_step == sum(steps for steps, _ in counted) <= config.total_steps
    for steps, lengths in counted:
        assert steps == POPSIZE * lengths.max()
    assert any(lengths.min() < 15 for _, lengths in counted)  # some robot fell


@pytest.mark.parametrize(
    "overrides, lines",
    [
        (["es.sigma0=0"], ["es.sigma0 must be a finite number > 0"]),
        (
            ["es.popsize=1", "es.episodes=0", "es.sigma0=.nan"],
            ["es.sigma0 must be", "es.popsize must be an integer from 2 to 10,000, got 1",
             "es.episodes must be an integer from 1 to 1,000, got 0"],
        ),
        (["es.popsize=3.5"], ["es.popsize must be an integer"]),
    ],
)  # fmt: skip
def test_bad_search_settings_are_one_clear_line_each(overrides, lines, tmp_path, capsys):
    with pytest.raises(ValueError) as error:
        compose_config(values={"agent": "open-loop-es"}, overrides=overrides)
    message = str(error.value).splitlines()
    assert len(message) == len(lines)
    for line, expected in zip(message, lines, strict=True):
        assert expected in line
    sets = [arg for text in overrides for arg in ("--set", text)]
    assert main(["train", "--run-dir", str(tmp_path / "r"), *TINY, *sets]) == 2
    assert lines[0] in capsys.readouterr().err
    assert not (tmp_path / "r").exists()


def test_the_gait_file_round_trips_into_an_agent_and_bad_ones_are_clear_errors(tmp_path):
    run = tmp_path / "run"
    assert main(["train", "--run-dir", str(run), *TINY, "--total-steps", str(2 * GENERATION)]) == 0
    gait = load_gait(run / "gait.yaml")
    assert gait == load_gait(run)  # a run directory names its gait file
    assert gait["robot"] == "hopper" and gait["seed"] == 0
    assert gait["steps_searched"] == 2 * GENERATION and gait["generation"] in (1, 2)
    assert set(gait["cpg_initial"]) == {
        "frequency", "amplitude", "convergence", "coupling_weight", "phase_bias",
    }  # fmt: skip
    # an agent started from the file has the search's V, to the last bit
    policy = load_policy(run)
    config = TrainConfig(agent="cpg-actor-open-loop")
    # the search's agent settings (on the hopper its V is inside the output bound)
    config.agent_config = TrainConfig.load(run / "config.yaml").agent_config
    config.agent_config.cpg_initial = gait["cpg_initial"]
    env = make_env(config, get_robot(config.robot), 1, None)
    try:
        agent = get_agent_spec(config.agent).build(config.agent_config, env, get_robot("hopper"))
    finally:
        env.close()
    searched = policy.agent.cpg.parametrisation.vector
    assert torch.equal(agent.cpg.parametrisation.vector, searched)
    # ... and write_gait / load_gait round-trip
    assert load_gait(write_gait(tmp_path / "copy.yaml", gait)) == gait

    with pytest.raises(FileNotFoundError, match="does not exist"):
        load_gait(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    for text, message in (
        ("robot: [unclosed", "not valid YAML"),
        ("- a list", "must hold a mapping"),
        ("robot: hopper\nfitness: 1.0\nseed: 0\ncpg_initial: {}", "lacks steps"),
    ):
        bad.write_text(text)
        with pytest.raises(ValueError, match=message):
            load_gait(bad)
    for change, message in (
        ({"frequency": [1.0, -2.0]}, "frequency must be > 0"),
        ({"amplitude": [0.1, 0.2, 0.3]}, "disagree on the number of oscillators"),
        ({"phase_bias": [[0.0, 1.0]]}, "phase_bias must be a number or an N x N list"),
        ({"stiffness": 1.0}, "unknown CPG parameters stiffness"),
    ):
        broken = {**gait, "cpg_initial": {**gait["cpg_initial"], **change}}
        with pytest.raises(ValueError, match=message):
            write_gait(bad, broken)


def test_eval_export_and_load_policy_work_on_a_search_run(tmp_path, capsys):
    run = tmp_path / "run"
    args = [*TINY, "--total-steps", str(2 * GENERATION), "--set", "eval_interval=1"]
    assert main(["train", "--run-dir", str(run), *args]) == 0
    assert "best return" in capsys.readouterr().out
    assert main(["eval", str(run), "--episodes", "2"]) == 0
    traces = np.load(run / "eval" / "traces.npz")
    assert traces["desired_position"].shape[1:] == (2, 2)
    assert np.all(traces["xi"][np.isfinite(traces["xi"])] == 0)  # open loop
    assert main(["export", str(run), "--format", "torchscript"]) == 0
    assert (run / "export" / "policy.pt").is_file()
    policy = load_policy(run)
    assert policy.config.agent == "open-loop-es" and policy.agent.feedback is None
    # the kept agent's evaluation is the last logged one
    last = metrics(run)[-1]
    assert traces["episode_return"].shape == (2,) and "eval/return" in last


def test_reproduce_plans_a_search_run_in_generations(tmp_path):
    from cpg_actor_studies.reproduction.plan import (
        ReproduceSettings,
        build_tasks,
        planned_iterations,
    )

    settings = ReproduceSettings(
        variants=["open-loop-es"], seeds=1, total_steps=100_000, overrides=["es.popsize=10"]
    )
    (task,) = build_tasks(settings, tmp_path, workers=1)
    assert task.num_iterations == 100_000 // (10 * 500) == 20
    assert task.planned_steps == 100_000
    assert "checkpoint_interval=1" in task.train_args
    config = compose_config(values={"agent": "open-loop-es"})
    assert planned_iterations(config) == (500_000 // 8000, 8000)


def test_a_search_cma_es_ended_stops_there_and_resume_says_so(tmp_path, capsys, monkeypatch):
    """CMA-ES's own termination (here made to fire after two generations) ends the run
    before its budget, with a final checkpoint and gait; resuming it is not an error."""
    monkeypatch.setattr(
        CMASearch, "stop_reason", property(lambda self: "tolx=1e-11" * (self.generation >= 2))
    )
    run = tmp_path / "run"
    assert main(["train", "--run-dir", str(run), *TINY, "--total-steps", str(5 * GENERATION)]) == 0
    assert "CMA-ES stopped: tolx=1e-11" in capsys.readouterr().out
    assert load_checkpoint(run / "checkpoints" / "last.pt")["iteration"] == 2
    assert load_gait(run)["steps_searched"] == 2 * GENERATION
    assert main(["train", "--run-dir", str(run), "--resume", "--no-progress"]) == 0
    assert "nothing to continue" in capsys.readouterr().out
