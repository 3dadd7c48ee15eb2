"""Recipes, the named starting points of a training run: ``cpg-actor train --preset NAME``.

A recipe is a set of config values applied over :class:`cpg_actor.config.TrainConfig`'s
defaults and the agent's tuned settings on the robot (``Robot.agent_defaults``), before
``--config``, the flags and ``--set`` (which all win over it); its name is saved in the run's
``config.yaml`` (``preset``). A recipe names no robot: each robot names the recipe its runs
follow when none is given (``Robot.recipe``: the hopper ``paper``, the quadrupeds
``throughput``), so ``--robot NAME`` alone trains with that robot's tuned settings.

* ``paper``: OpenAI Baselines' ppo2 settings for MuJoCo tasks, the framework the paper used
  (every number and its source: :class:`cpg_actor.ppo.PPOConfig`). These are the dataclass
  defaults; the recipe only adds ``ppo.compile`` (the same algorithm, its gradient step,
  the rollout's policy step and reward scaling compiled by ``torch.compile`` into fewer,
  fused kernels).
* ``throughput``: the massively parallel recipe of legged_gym / rsl_rl (Rudin et al. 2021):
  many envs, short rollouts, few large minibatches, a learning rate adapted to a target KL.
  256 envs x 32 steps = 8,192 samples per iteration, 5 epochs of 4 minibatches (20 gradient
  steps per 8,192 samples; paper: 320 per 2,048), learning rate 1e-3 adapted to KL 0.01, the
  CPG and its feedback at a fixed 3e-4 outside that schedule (``ppo.cpg_learning_rate``: the
  KL the schedule follows hardly sees them, so its rate, up to 1e-2, would drive them). It
  spends a small CPU's time on the physics rather than the update and learns less per
  sample; what it reaches and when: ``docs/training.md``, "Presets". The quadrupeds' recipe.
* ``gpu``: the same recipe at GPU scale on the MJX simulator (``docs/gpu.md``): 4,096 envs x 24
  steps = 98,304 samples per iteration (legged_gym's rollout length for 4,096 envs), 5 epochs
  of 4 minibatches of 24,576, learning rate 1e-3 adapted to KL 0.01 and the CPG's own 3e-4
  as ``throughput`` (no effect on agents whose policy holds no CPG: ``mlp``, ``cho2019*``);
  ``device`` auto (CUDA if torch sees it). It runs on a CPU too (JAX's CPU backend), slowly.

* ``omni``: the quadrupeds' omnidirectional velocity task on the ``throughput`` recipe: the
  env's commands are the robot's ``OMNI_COMMANDS`` (its config class's: the field's ranges,
  vx in [-1, 1] m/s, vy in [-0.5, 0.5] m/s, yaw rate in [-1, 1] rad/s, drawn again every 5 s,
  one draw in ten standing still; ``docs/quadruped.md``, "The omnidirectional task"), and the
  CPG's drive follows the whole command (``agent_config.cpg_planar_steps``: each leg's step
  along its foot's commanded planar velocity). A robot without ``OMNI_COMMANDS`` (the hopper)
  has no such task: ValueError.

* ``playground``: MuJoCo Playground's Go1 joystick recipe as its source runs it (the
  ``playground`` package 0.2.0, Go1JoystickFlatTerrain, trained by rsl_rl): the env's values
  are the robot's ``PLAYGROUND`` (the Go1's: ``robots/go1/playground.py``, each with its
  source: PD 35 / 0.5, actions home + 0.5 a, the reward's terms and scales clipped at 0, the
  base's linear velocity and uniform noise in the observation, a privileged critic, the
  command process); the PPO's are rsl_rl's recipe from ``config/locomotion_params.py``
  (:data:`PLAYGROUND`). For the ``mlp`` agents (``mlp``, ``mlp-warm``: their privileged
  critic, ``env.privileged_observation``); ``docs/go1.md``, "MuJoCo Playground's recipe". A
  robot without ``PLAYGROUND``: ValueError.

* ``legged_gym``: legged_gym's ANYmal B recipe as its source runs it (leggedrobotics/
  legged_gym, ``AnymalBRoughCfg`` on flat ground, trained by rsl_rl v1.0.2): the env's values
  are the robot's ``LEGGED_GYM`` (ANYmal B's: ``robots/common/quadruped/legged_gym.py``,
  each with its source: PD 80 / 2, actions default + 0.5 a, 5 ms x 4, the reward's scales
  clipped at 0, the base's linear velocity and uniform noise in the observation, the heading
  command, the start, the randomisation); the PPO's are rsl_rl's as legged_gym runs ANYmal
  (:data:`LEGGED_GYM`), its scaled, unnormalised observation included
  (``agent_config.observation_scales``). For the ``mlp`` agents; ``docs/quadruped.md``,
  "legged_gym's recipe". A robot without ``LEGGED_GYM`` (the Go1, the hopper): ValueError.

``anymal`` is the name ANYmal B's recipe had when presets named robots, kept so that saved runs
(``preset: anymal``) and their commands keep their values: ``robot: anymal``, ``throughput``
and the CPG-Actor's settings for every agent (one oscillator per leg, action noise 0.1, feedback
noise 0.2). ``--robot anymal`` alone now gives the same to ``cpg-actor``.
"""

from __future__ import annotations

from typing import Any

from cpg_actor.limits import brief

# the observation's fixed scales (LeggedRobotCfg.normalization.obs_scales: lin_vel 2, ang_vel
# 0.25, dof_pos 1, dof_vel 0.05; the commands x (2, 2, 0.25), commands_scale) as entry-name
# patterns of the velocity task's observation (agent_config.observation_scales; rsl_rl v1 normalises
# nothing). legged_gym observes the action a itself, this env the target's offset 0.5 a: x 2
LEGGED_GYM_OBSERVATION_SCALES: dict[str, float] = {
    "base_lin_vel_*": 2.0,
    "base_ang_vel_*": 0.25,
    "command_vx": 2.0,
    "command_vy": 2.0,
    "command_yaw": 0.25,
    "*_vel": 0.05,  # the joints' speeds
    "*_last_action": 2.0,  # 1 / action_scale
}

# the fixed learning rate of what acts through the CPG (ppo.cpg_learning_rate): the paper's
CPG_LEARNING_RATE = 3e-4

THROUGHPUT: dict[str, Any] = {
    "num_envs": 256,
    "eval_interval": 10,
    "ppo": {
        "num_steps": 32,
        "num_epochs": 5,
        "num_minibatches": 4,
        "lr_schedule": "adaptive",
        "learning_rate": 1e-3,
        "cpg_learning_rate": CPG_LEARNING_RATE,
        "compile": True,
    },
}

# a recipe's key naming a class attribute of the robot's env config whose values are the
# recipe's env values on that robot (its own command ranges)
ROBOT_ENV = "robot_env"

# rsl_rl's PPO as MuJoCo Playground 0.2.0 runs it on Go1JoystickFlatTerrain
# (config/locomotion_params.py, rsl_rl_config; learning/train_rsl_rl.py). Departures, forced
# by a CPU: 256 envs (its script's default: 4,096), so 6,144 samples per iteration in
# minibatches of 1,536; and by this codebase: the advantages normalised per minibatch (rsl_rl:
# over the whole batch), the actor's last layer initialised small (the mean starts at the
# home pose; rsl_rl: PyTorch's default init)
PLAYGROUND: dict[str, Any] = {
    "num_envs": 256,
    "eval_interval": 10,
    "agent_config": {
        "actor_hidden": [512, 256, 128],  # actor_hidden_dims
        "critic_hidden": [512, 256, 128],  # critic_hidden_dims
        "activation": "elu",
        "init_std": 1.0,  # init_noise_std, in units of the action (0.5 rad: action_scale)
        "action_std_floor": 0.0,  # none in rsl_rl
    },
    "ppo": {
        "num_steps": 24,  # num_steps_per_env
        "num_epochs": 5,  # num_learning_epochs
        "num_minibatches": 4,  # num_mini_batches
        "learning_rate": 3e-4,  # Go1JoystickFlatTerrain: 3e-4, schedule fixed
        "lr_schedule": "fixed",
        "entropy_coef": 0.001,  # entropy_coef (its Brax recipe: 0.01)
        "gamma": 0.99,
        "gae_lambda": 0.95,  # lam
        "clip_ratio": 0.2,  # clip_param
        "clip_value_loss": True,  # use_clipped_value_loss
        "value_loss_coef": 1.0,
        "max_grad_norm": 1.0,
        "normalize_observations": True,  # empirical_normalization (actor's and critic's)
        "normalize_rewards": False,  # rsl_rl scales no reward
        "adam_eps": 1e-8,  # torch's Adam default, as rsl_rl builds it
        "compile": True,
    },
    ROBOT_ENV: "PLAYGROUND",
}

# rsl_rl's PPO (v1.0.2, the version legged_gym's README pins: algorithms/ppo.py, modules/
# actor_critic.py, runners/on_policy_runner.py) as legged_gym runs ANYmal B (LeggedRobotCfgPPO,
# which AnymalCRoughCfgPPO and AnymalBRoughCfgPPO keep). Departures, forced by a CPU: 256 envs
# (its default: 4,096), so 6,144 samples per iteration in minibatches of 1,536; and by this
# codebase: the advantages normalised per minibatch (rsl_rl: over the whole batch), the
# networks initialised orthogonally, the actor's last layer small (the mean starts at the
# default pose; rsl_rl: PyTorch's default init), the action noise a trained log-std (rsl_rl:
# the std itself), time-outs bootstrapped from the last observation's value (rsl_rl: reward
# + gamma V(s) of the step's own observation), every env starting at step 0 (legged_gym's
# train.py: init_at_random_ep_len), the observation not clipped (legged_gym: at +-100, which
# its scaled entries do not reach)
LEGGED_GYM: dict[str, Any] = {
    "num_envs": 256,
    "eval_interval": 10,
    "agent_config": {
        "actor_hidden": [512, 256, 128],  # policy.actor_hidden_dims
        "critic_hidden": [512, 256, 128],  # policy.critic_hidden_dims
        "activation": "elu",
        "init_std": 1.0,  # init_noise_std, in units of a (0.5 rad: env.action_scale)
        "action_std_floor": 0.0,  # none in rsl_rl
        # normalization.obs_scales (above): rsl_rl v1 normalises nothing
        "observation_scales": LEGGED_GYM_OBSERVATION_SCALES,
    },
    "ppo": {
        "num_steps": 24,  # runner.num_steps_per_env
        "num_epochs": 5,  # algorithm.num_learning_epochs
        "num_minibatches": 4,  # algorithm.num_mini_batches
        "learning_rate": 1e-3,  # algorithm.learning_rate
        "lr_schedule": "adaptive",  # algorithm.schedule
        "desired_kl": 0.01,  # algorithm.desired_kl
        "min_learning_rate": 1e-5,  # PPO.update: max(1e-5, lr / 1.5)
        "max_learning_rate": 1e-2,  # PPO.update: min(1e-2, lr * 1.5)
        "entropy_coef": 0.01,  # algorithm.entropy_coef
        "gamma": 0.99,
        "gae_lambda": 0.95,  # algorithm.lam
        "clip_ratio": 0.2,  # algorithm.clip_param
        "clip_value_loss": True,  # algorithm.use_clipped_value_loss
        "value_loss_coef": 1.0,
        "max_grad_norm": 1.0,
        "normalize_observations": False,  # no normaliser in rsl_rl v1: the env's scales
        "normalize_rewards": False,  # rsl_rl scales no reward
        "adam_eps": 1e-8,  # torch's Adam default, as rsl_rl builds it
        "compile": True,
    },
    ROBOT_ENV: "LEGGED_GYM",
}

# the recipes a user picks (--preset); PRESETS adds the old name kept for saved runs
RECIPES = ("paper", "throughput", "gpu", "omni", "playground", "legged_gym")

PRESETS: dict[str, dict[str, Any]] = {
    "paper": {"ppo": {"compile": True}},
    "throughput": THROUGHPUT,
    "gpu": {
        "num_envs": 4096,
        "device": "auto",
        "eval_interval": 10,
        "env": {"sim": "mjx"},
        "ppo": {**THROUGHPUT["ppo"], "num_steps": 24},
    },
    "omni": {
        **THROUGHPUT,
        ROBOT_ENV: "OMNI_COMMANDS",
        "agent_config": {"cpg_planar_steps": True},
    },
    "playground": PLAYGROUND,
    "legged_gym": LEGGED_GYM,
    "anymal": {  # ANYmal B's recipe under its old name, for saved runs (above)
        **THROUGHPUT,
        "robot": "anymal",
        "agent_config": {"cpg_layout": "leg", "init_std": 0.1, "feedback_noise": 0.2},
    },
}


def check_preset(name: str) -> None:
    """ValueError unless ``name`` is a recipe (or the old name kept for saved runs)."""
    if name not in PRESETS:
        raise ValueError(
            f"unknown preset {brief(name)}; the recipes are {', '.join(RECIPES)} (a robot's own: "
            "--robot NAME alone)"
        )


def preset_values(name: str, env_class: type | None = None) -> dict[str, Any]:
    """The config values of recipe ``name`` (a nested mapping); ValueError if unknown.
    ``env_class``: the robot's env config class, whose values a recipe may take
    (:data:`ROBOT_ENV`; None: the robot is not known yet, those values are left out)."""
    check_preset(name)
    values = {"preset": name, **PRESETS[name]}
    attribute = values.pop(ROBOT_ENV, None)
    if attribute is not None and env_class is not None:
        robot_env = getattr(env_class, attribute, None)
        if robot_env is None:
            raise ValueError(f"preset {brief(name)} is a task this robot does not define: its "
                             f"config {env_class.__name__} has no {attribute} (a robot whose "
                             f"config has one runs it)")  # fmt: skip
        values["env"] = {**values.get("env", {}), **robot_env}
    return values
