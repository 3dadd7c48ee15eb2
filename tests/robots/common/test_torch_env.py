"""The trainer's env contract: torch tensors on a declared device, the same numbers as the
wrapped numpy env."""

from __future__ import annotations

import numpy as np
import torch

from cpg_actor.robots.common.torch_env import TorchVectorEnv
from cpg_actor.robots.hopper.config import HopperConfig
from cpg_actor.robots.hopper.vector import HopperVectorEnv


def test_tensors_in_and_out_match_the_wrapped_env():
    config = HopperConfig(episode_steps=3)
    reference = HopperVectorEnv(2, config)
    env = TorchVectorEnv(HopperVectorEnv(2, config), "cpu")
    try:
        assert env.robot == reference.robot and env.num_envs == 2
        obs, _ = env.reset(seed=7)
        ref_obs, _ = reference.reset(seed=7)
        assert obs.dtype == torch.float32 and obs.device == torch.device("cpu")
        np.testing.assert_array_equal(obs.numpy(), ref_obs)
        actions = np.tile(np.array(env.robot.nominal_pose, dtype=np.float32), (2, 1))
        for t in range(4):
            # numpy actions and tensor actions are both accepted
            out = env.step(torch.as_tensor(actions) if t % 2 else actions)
            ref_obs, ref_reward, ref_term, ref_trunc, ref_info = reference.step(actions)
            np.testing.assert_array_equal(out.obs.numpy(), ref_obs)
            assert out.reward.dtype == torch.float64  # the simulator's own precision
            np.testing.assert_array_equal(out.reward.numpy(), ref_reward)
            assert out.terminated.dtype == torch.bool and out.truncated.dtype == torch.bool
            np.testing.assert_array_equal(out.truncated.numpy(), ref_trunc)
            np.testing.assert_array_equal(out.terminated.numpy(), ref_term)
            np.testing.assert_array_equal(out.final_obs.numpy(), ref_info["final_obs"])
            hop = out.episode_metrics["hop_height"].numpy()
            np.testing.assert_array_equal(hop, ref_info["episode_metrics"]["hop_height"])
            assert set(out.reward_terms) == set(ref_info["reward_terms"])
            if t == 2:  # the 3-step episodes end here: final observations differ from obs
                assert out.truncated.all() and np.isfinite(hop).all()
                assert not torch.equal(out.final_obs, out.obs)
    finally:
        env.close()
        reference.close()
