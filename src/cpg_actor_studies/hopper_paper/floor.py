"""The open-loop grid floor: what a grid search over constant CPG parameters reaches with no
learning at all, for a reproduction's environment.

The open-loop CPG-Actor learns constant CPG parameters; a grid over the same parameters
(the studied robot's ``Paper.open_loop_floor``; the hopper's: 960 sets of frequency, hip and
knee amplitude and hip-knee phase bias, a and w at the preset's values) run for one episode each
with no reset noise gives a floor any CPG agent's trained return should clear. The report
shows it next to the trained variants (``OUT/open_loop_floor.json``).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

FLOOR_FILE = "open_loop_floor.json"


def open_loop_floor(env_config: Any, grid: dict | None = None) -> dict[str, Any]:
    """The best grid candidate by episode return (and, for reference, by hop height);
    ``grid`` entries replace those of the default grid. The grid is the robot's that
    ``env_config`` configures (its ``Robot.paper``)."""
    from cpg_actor.api import robot_of_config

    return robot_of_config(env_config).paper_parts().open_loop_floor(env_config, grid)


def write_floor(out: Path, env_config: Any) -> dict[str, Any]:
    """Compute the floor for ``env_config`` and save it in ``out`` (atomically)."""
    from cpg_actor.api import atomic_write_text

    floor = open_loop_floor(env_config)
    floor["env"] = env_config.to_dict()
    atomic_write_text(json.dumps(floor, indent=1) + "\n", Path(out) / FLOOR_FILE)
    return floor


def ensure_floor(out: Path, settings: Any) -> dict[str, Any]:
    """The floor of a reproduction
    (:class:`~cpg_actor_studies.reproduction.plan.ReproduceSettings`), computed once for its
    environment (:func:`floor_env_config`) and then reused."""
    floor = load_floor(out)
    if floor is None:
        floor = write_floor(out, floor_env_config(out, settings))
    return floor


def floor_env_config(out: Path, settings: Any) -> Any:
    """The env the runs in ``out`` trained on (the saved config of a ``cpg-actor-open-loop``
    or ``cpg-actor`` run, else of any run: a run saved before an option existed keeps what it
    trained with), or else what ``settings`` resolve to; always with eq. 4's reward."""
    from cpg_actor.api import TrainConfig
    from cpg_actor_studies.reproduction.plan import resolve_config

    runs = Path(out) / "runs"
    paths = [
        *sorted(runs.glob("cpg-actor-open-loop/seed*/config.yaml")),
        *sorted(runs.glob("cpg-actor/seed*/config.yaml")),
        *sorted(runs.glob("*/seed*/config.yaml")),
    ]
    if paths:
        env = TrainConfig.load(paths[0]).env
    else:
        env = resolve_config(settings, "cpg-actor-open-loop").env
    return env.replace(hop_reward="hip-velocity")


def load_floor(out: Path) -> dict[str, Any] | None:
    path = Path(out) / FLOOR_FILE
    if not path.is_file():
        return None
    try:
        return json.loads(path.read_text())
    except (json.JSONDecodeError, OSError):
        return None
