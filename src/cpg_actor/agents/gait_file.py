"""The gait file (``gait.yaml``): a CPG's parameters in physical units, as
``agent_config.cpg_initial`` takes them, so that another agent can start from them.

The open-loop search (``open-loop-es``) writes one in its run directory at every checkpoint
and at the end: the best candidate found so far, with the robot, its fitness (the mean
undiscounted return it was selected on), the env steps the search had used, the generation
and the run seed::

    format: cpg-actor-gait
    robot: hopper
    cpg_layout: joint
    cpg_gait: ''
    fitness: ...
    episodes: 1
    steps: ...
    generation: ...
    seed: 0
    cpg_initial:
      frequency: [nu_1, ..., nu_N]          # Hz
      amplitude: [rho_1, ..., rho_N]        # rad
      convergence: [a_1, ..., a_N]          # 1/s
      coupling_weight: [[w_11, ...], ...]   # N x N
      phase_bias: [[phi_11, ...], ...]      # N x N, rad
      # frequency_gain, amplitude_gain: where the CPG has a drive gain (eq. 3)

:func:`load_gait` reads and checks one: ``agent_config.cpg_initial = load_gait(path)
["cpg_initial"]`` starts a CPG-Actor there.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import yaml

from cpg_actor.limits import brief
from cpg_actor.safe_yaml import read_yaml

GAIT_FILE = "gait.yaml"
GAIT_FORMAT = "cpg-actor-gait"
VECTOR_FIELDS = ("frequency", "amplitude", "convergence")
MATRIX_FIELDS = ("coupling_weight", "phase_bias")
GAIN_FIELDS = ("frequency_gain", "amplitude_gain")
POSITIVE_FIELDS = VECTOR_FIELDS  # > 0; the gains >= 0
REQUIRED_KEYS = ("robot", "fitness", "steps", "seed", "cpg_initial")


def gait_parameters(agent: Any) -> dict[str, list]:
    """The physical CPG parameters of ``agent`` (a :class:`CPGActorAgent`) as
    ``cpg_initial`` takes them: nu, rho, a per oscillator, W and Phi as N x N lists, and the
    drive gains where they are not 0. Computed from V in float64, so that the file gives V
    back to its last bit."""
    parametrisation = copy.deepcopy(agent.cpg.parametrisation).double()
    values = {key: value.detach().cpu() for key, value in parametrisation.values().items()}
    out = {field: values[field].tolist() for field in (*VECTOR_FIELDS, *MATRIX_FIELDS)}
    for field in GAIN_FIELDS:
        if bool((values[field] != 0).any()):
            out[field] = values[field].tolist()
    return out


def gait_text(gait: dict[str, Any]) -> str:
    header = (
        "# cpg-actor gait: CPG parameters in physical units (agent_config.cpg_initial);\n"
        "# fitness: the mean undiscounted episode return the search selected it on\n"
    )
    return header + yaml.safe_dump(gait, sort_keys=False, default_flow_style=None)


def write_gait(path: str | Path, gait: dict[str, Any]) -> Path:
    """Write ``gait`` (a mapping of :data:`REQUIRED_KEYS` and more) to ``path`` atomically,
    after checking it as :func:`load_gait` would."""
    from cpg_actor.files import atomic_write_text

    path = Path(path)
    gait = {"format": GAIT_FORMAT, **gait}
    check_gait(gait, str(path))
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(gait_text(gait), path)
    return path


def load_gait(path: str | Path) -> dict[str, Any]:
    """The gait in ``path`` (a gait file, or a run directory holding ``gait.yaml``), checked:
    a mapping with ``robot``, ``fitness``, ``steps``, ``seed`` and ``cpg_initial`` (the
    parameters, see the module docstring). FileNotFoundError if it does not exist, ValueError
    naming what is wrong otherwise."""
    path = Path(path)
    if path.is_dir():
        path = path / GAIT_FILE
    if not path.is_file():
        raise FileNotFoundError(f"gait file {path} does not exist")
    data = read_yaml(path, f"gait file {path}")  # bounded (cpg_actor.safe_yaml), one line
    check_gait(data, str(path))
    return data


def check_gait(data: Any, name: str) -> None:
    """ValueError naming the first thing wrong with a gait mapping."""
    if not isinstance(data, dict):
        raise ValueError(f"gait file {name} must hold a mapping (robot, cpg_initial, ...)")
    if data.get("format", GAIT_FORMAT) != GAIT_FORMAT:
        raise ValueError(
            f"gait file {name}: format {brief(data['format'])}, expected {GAIT_FORMAT!r}"
        )
    missing = [key for key in REQUIRED_KEYS if key not in data]
    if missing:
        raise ValueError(f"gait file {name} lacks {', '.join(missing)}")
    if not isinstance(data["robot"], str) or not data["robot"]:
        raise ValueError(
            f"gait file {name}: robot must be a robot's name, got {brief(data['robot'])}"
        )
    fitness = data["fitness"]
    if isinstance(fitness, bool) or not isinstance(fitness, (int, float)):
        raise ValueError(f"gait file {name}: fitness must be a number, got {brief(fitness)}")
    for key in ("steps", "seed"):
        value = data[key]
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise ValueError(f"gait file {name}: {key} must be an integer >= 0, got {brief(value)}")
    _check_parameters(data["cpg_initial"], name)


def _check_parameters(parameters: Any, name: str) -> None:
    if not isinstance(parameters, dict):
        raise ValueError(f"gait file {name}: cpg_initial must be a mapping of CPG parameters")
    known = (*VECTOR_FIELDS, *MATRIX_FIELDS, *GAIN_FIELDS)
    unknown = sorted(set(parameters) - set(known))
    if unknown:
        raise ValueError(
            f"gait file {name}: unknown CPG parameters {', '.join(map(str, unknown))}; "
            f"accepted: {', '.join(known)}"
        )
    missing = [field for field in VECTOR_FIELDS if field not in parameters]
    if missing:
        raise ValueError(f"gait file {name}: cpg_initial lacks {', '.join(missing)}")
    sizes = set()
    for field, value in parameters.items():
        matrix = field in MATRIX_FIELDS
        rows = value if isinstance(value, list) else None
        if rows is None:  # a scalar, broadcast to every entry
            numbers = [value]
        elif matrix:
            if not all(isinstance(row, list) and len(row) == len(rows) for row in rows):
                raise ValueError(f"gait file {name}: {field} must be a number or an N x N list")
            numbers = [x for row in rows for x in row]
            sizes.add(len(rows))
        else:
            numbers = rows
            sizes.add(len(rows))
        for x in numbers:
            if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
                raise ValueError(
                    f"gait file {name}: {field} must hold finite numbers, got {brief(value)}"
                )
        if field in POSITIVE_FIELDS and any(x <= 0 for x in numbers):
            raise ValueError(f"gait file {name}: {field} must be > 0, got {brief(value)}")
        if field in GAIN_FIELDS and any(x < 0 for x in numbers):
            raise ValueError(f"gait file {name}: {field} must be >= 0, got {brief(value)}")
    if len(sizes) > 1 or 0 in sizes:
        raise ValueError(
            f"gait file {name}: the CPG parameters disagree on the number of oscillators "
            f"({', '.join(map(str, sorted(sizes)))})"
        )
