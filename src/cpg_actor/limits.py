"""The bounds on every count and size a config or a flag can set, in one place, and
:func:`brief`, the bounded text of a value an error message quotes (no torch: the CLI imports
this).

Each bound is far above what any real run uses, and low enough that a typo or a hostile value
(a million seeds, 1e8 envs, a hidden layer of a million units) is refused in one line by the
config's validation, before an env is built or a file written, instead of hanging the machine
or exhausting its memory.
"""

from __future__ import annotations

import reprlib
from typing import Any

# -- counts and sizes -----------------------------------------------------------------------
# the largest seed: torch takes seeds below 2**64, but seeds pass through int64 tensors and
# arrays (checkpoints, env seeds), so the accepted range is that of an int64
MAX_SEED = 2**63 - 1
# seeds one command trains (train --seeds, reproduce and sweep --seeds): 2,000 times the
# paper's 5
MAX_SEEDS = 10_000
# runs side by side on one machine (reproduce and sweep --workers)
MAX_WORKERS = 1_024
# control steps of a run (total_steps): years of training on any machine
MAX_STEPS = 10**12
# environments stepped together (num_envs; --seeds x num_envs; es.popsize x es.episodes): 64
# times the GPU preset's 4,096
MAX_ENVS = 2**18
# episodes an evaluation runs at most (in parallel, an env each): far beyond the 4 to 5 its
# commands run by default, small enough for the envs to fit in memory
MAX_EPISODES = 1_000
# control steps per env in one rollout (ppo.num_steps, warm_start.rollout_steps)
MAX_ROLLOUT_STEPS = 2**16
# samples one rollout stores, envs x steps (num_envs x ppo.num_steps, and the warm start's):
# 8,192 times the paper's 2,048, a few GB of observations, actions and states
MAX_ROLLOUT_SAMPLES = 2**24
# passes over one batch (ppo.num_epochs, warm_start.epochs): 1,000 times the paper's 10
MAX_EPOCHS = 10_000
# a network's hidden layers (agent_config.actor_hidden, critic_hidden; the feedback MLP takes
# the actor's): the units of one, how many, and the weights between two (1 GiB of float32)
MAX_LAYER_WIDTH = 65_536
MAX_LAYERS = 64
MAX_LAYER_WEIGHTS = 2**28
# threads a run asks for (torch_threads, update_threads, env_threads)
MAX_THREADS = 4_096
# control steps per episode: 200 times the hopper's and the quadrupeds' episodes
MAX_EPISODE_STEPS = 100_000
# physics substeps per control step (env.decimation): 100 times the defaults
MAX_DECIMATION = 1_000
# the MJX constraint solver's iteration caps (env.mjx_iterations, mjx_ls_iterations): 10
# times MuJoCo's default of 100
MAX_SOLVER_ITERATIONS = 1_000
# pixels of a rendered frame's side (env.render_width, render_height): beyond 8K video
MAX_RENDER_SIZE = 8_192
# rough ground (env.terrain): difficulty levels, and the height samples of its whole map
# (levels x kinds tiles and the border, at terrain.resolution): 50 times the default map's
MAX_TERRAIN_LEVELS = 1_000
MAX_TERRAIN_SAMPLES = 2**25
# candidates of one CMA-ES generation (es.popsize): 600 times the default 16
MAX_POPSIZE = 10_000
# the text of a YAML file or value (a run's config.yaml has a few KB), its nodes with every
# alias expanded (a "billion laughs" file expands a few lines into billions), how deep it
# nests (a config nests 4 levels)
MAX_YAML_BYTES = 2**20
MAX_YAML_NODES = 100_000
MAX_YAML_DEPTH = 100


def check_int(value: Any, name: str, low: int, high: int) -> None:
    """ValueError (one line: the field, the value, the accepted range) unless ``value`` is an
    integer (not a bool) from ``low`` to ``high``."""
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise ValueError(f"{name} must be an integer from {low:,} to {high:,}, got {brief(value)}")


# -- bounded text of a value ----------------------------------------------------------------
MAX_BRIEF = 200  # characters of brief()'s text at most


class _Brief(reprlib.Repr):
    """``reprlib``'s bounded repr, with integers of any size (Python refuses to write one of
    more than 4,300 digits) and strings cut short."""

    def __init__(self) -> None:
        super().__init__()
        self.maxlevel = 3
        self.maxtuple = self.maxlist = self.maxarray = self.maxdict = 8
        self.maxset = self.maxfrozenset = self.maxdeque = 8
        self.maxstring = 80
        self.maxlong = 40
        self.maxother = 80

    def repr_int(self, x: int, level: int) -> str:
        if x.bit_length() > 128:  # its digits are not worth writing (nor quick to)
            return f"<an integer of {x.bit_length() * 0.30103:.0f} digits>"
        return super().repr_int(x, level)


_BRIEF = _Brief()


def brief(value: Any) -> str:
    """``repr(value)`` in at most :data:`MAX_BRIEF` characters, built without walking more
    than a few items of each container: safe for an error message quoting what a user gave
    (a huge list, a deeply nested structure, a long string)."""
    try:
        text = _BRIEF.repr(value)
    except Exception:  # an object whose repr fails
        text = f"<{type(value).__name__}>"
    return text if len(text) <= MAX_BRIEF else text[: MAX_BRIEF - 3] + "..."


def shorten(text: str, limit: int = MAX_BRIEF) -> str:
    """``text`` cut to ``limit`` characters (a key, a name, a message quoted in another)."""
    text = str(text)
    return text if len(text) <= limit else text[: limit - 3] + "..."
