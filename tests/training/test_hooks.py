"""The loop's hooks: the order they are called in, what they see, a hook that stops the run,
and the capabilities an env declares (fake env)."""

from types import SimpleNamespace

import torch

from cpg_actor.robots.common.torch_env import SavableEnv, TensorEnv, TorchVectorEnv
from cpg_actor.training.hooks import Hook
from ppo.fake_env import FakeHopperVectorEnv

from .test_runner import config, params, runner


class Recorder(Hook):
    def __init__(self, stop_at=None):
        self.calls, self.stop_at = [], stop_at

    def start(self, runner, fresh):
        self.calls.append(("start", fresh, runner.last_evaluation is not None))

    def iteration(self, runner, it):
        self.calls.append(("iteration", it.number, it.last, it.evaluation is not None))
        assert it.number == runner.iteration and it.stats["learning_rate"] > 0
        assert it.timing["SPS"] > 0 and runner.last_row  # logged before this hook
        if it.number == self.stop_at:
            it.stop = True

    def end(self, runner):
        self.calls.append(("end",))


def test_hooks_are_called_in_order_and_see_the_evaluations(tmp_path):
    recorder = Recorder()
    r = runner(config(3, eval_interval=2))
    r.hooks.append(recorder)
    r.learn()
    r.close()
    assert recorder.calls == [
        ("start", True, True),  # after the evaluation before the first iteration
        ("iteration", 1, False, False),
        ("iteration", 2, False, True),
        ("iteration", 3, True, True),  # the last iteration is evaluated
        ("end",),
    ]


def test_a_hook_that_stops_the_run_gets_a_checkpoint_and_changes_no_numbers(tmp_path):
    plain = runner(config(5))  # the same budget (the learning rate decays to it), no hooks
    plain.start_episodes()
    plain.train_iteration()
    plain.train_iteration()
    stopping = runner(config(5, interval=10), run_dir=tmp_path / "run")
    stopping.hooks.append(Recorder(stop_at=2))
    stopping.learn()
    assert stopping.iteration == 2
    assert sorted(p.name for p in (tmp_path / "run" / "checkpoints").iterdir()) == [
        "iter_000000.pt", "iter_000002.pt", "last.pt"]  # fmt: skip
    for key, value in params(plain).items():
        assert torch.equal(value, params(stopping)[key]), key
    plain.close()
    stopping.close()


def test_env_capabilities_are_declared_by_protocols():
    fake = FakeHopperVectorEnv(2)
    assert isinstance(fake, SavableEnv) and not isinstance(fake, TensorEnv)
    wrapped = TorchVectorEnv(fake)
    assert wrapped.saves_state and not wrapped.has_tensor_face
    spaces = fake.single_observation_space, fake.single_action_space
    no_state = SimpleNamespace(num_envs=2, robot=fake.robot, single_observation_space=spaces[0],
                               single_action_space=spaces[1])  # fmt: skip
    assert not TorchVectorEnv(no_state).saves_state
