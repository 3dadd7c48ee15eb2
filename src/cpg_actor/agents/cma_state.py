"""A CMA-ES search's state as plain arrays and numbers, and a search rebuilt from them.

A checkpoint holds no pickle of the search: an allow-list of classes cannot make unpickling
safe when the classes do I/O (cma's logger writes files, its options are evaluated). Instead,
:func:`search_state` reads what ``cma.CMAEvolutionStrategy`` changes as it runs into a dict of
float64 / int64 tensors and plain numbers (``torch.load(weights_only=True)`` reads them): the
mean and step size, the covariance matrix with its eigen decomposition, the evolution paths,
the counters, the fitness histories its stopping criteria read, the best solution, and the
state of the generator its normal draws come from (:class:`~.open_loop_es.NormalSource`).

:func:`restore_search_state` writes those numbers back into a search that cma's public
constructor built from the running run's own options (the file gives no option, class or
path). Each value is checked against the kind and shape it has in a search of this dimension
and population size before anything is written, so a bad state is refused whole, in one line.
The fields below are every value that changes while the search runs; a test checks that no
other one does, so a new ``cma`` that keeps more state fails it rather than resuming inexactly.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import torch

# where a field lives (attribute path from the search) and what it holds:
#   "n": float64 (N,)   "nn": float64 (N, N)   "ln": float64 (popsize, N)   "l": float64 (popsize,)
#   "index": int64 (popsize,)   "floats" / "bools": a list of at most MAX_HISTORY numbers
#   "rows": a list of at most popsize (N,) arrays, as float64 (k, N)   "range": [start, stop]
#   "float", "int": a number;  a trailing "?": may also be None (not set yet: an attribute
#   the constructor does not make stays unmade)
FIELDS: dict[str, str] = {
    "x0": "n",
    "mean0": "n",
    "sigma0": "float",
    "mean": "n",
    "mean_after_tell": "n",
    "mean_old": "n?",
    "mean_old_old": "n?",
    "sigma": "float",
    "_sigma_old": "float?",
    "pc": "n",
    "pc2": "n",
    "dC": "n",
    "ary": "ln?",
    "pop_sorted": "ln?",
    "_isotropic_mean_shift": "n?",
    "pop_injection_directions": "rows",
    "pop_injection_solutions": "rows",
    "_indices_of_selective_mirrors": "range?",
    "_mirrormethod1_done": "int?",
    "_isotropic_mean_shift_iteration": "int",
    "_is_independent_sample": "bools",
    "countiter": "int",
    "countevals": "int",
    "itereigenupdated": "int",
    "evaluations_per_f_value": "int?",
    "number_of_injections": "int?",
    "number_of_injections_delivered": "int",
    "number_of_solutions_asked": "int",
    "_stoptolxstagnation.count": "int",
    "_stoptolxstagnation.count_x": "int",
    "_stoptolxstagnation.x": "n?",
    "adapt_sigma.ps": "n",
    "adapt_sigma.delta": "float",
    "adapt_sigma._last_multiplier": "float?",
    "adapt_sigma._ps_updated_iteration": "int",
    "best.x": "n?",
    "best.x_geno": "n?",
    "best.f": "float",
    "best.evals": "int?",
    "best.evalsall": "int?",
    "best.compared": "int",
    "best.last.x": "n?",
    "best.last.f": "float",
    "fit.fit": "floats?",
    "fit.bndpen": "floats?",
    "fit.fit_plus_pen": "l?",
    "fit.idx": "index?",
    "fit.hist": "floats",
    "fit.histbest": "floats",
    "fit.histmedian": "floats",
    "fit.median": "float?",
    "fit.median0": "float?",
    "fit.median_min": "float?",
    "fit.median_previous": "float?",
    "fit.median_got_worse": "int",
    "fit.flatfit_iterations": "int",
    "sm.C": "nn",
    "sm.B": "nn",
    "sm.D": "n",
    "sm._inverse_root_C": "nn?",
    "sm.count_eigen": "int",
    "sm.count_tell": "int",
    "sm.last_update": "int",
    "sm._corr_condition_count_eigen": "int",
    "sent_solutions.last_iteration": "int",
    "sent_solutions.last_solution_index": "int",
}
# the search keeps these as the sampler's own arrays (one object, updated in place)
ALIASES = {"C": "sm.C", "B": "sm.B", "D": "sm.D"}
MAX_HISTORY = 100_000  # cma keeps at most 20,000 entries of its longest history
_GENERATOR = "randn"  # the normal source's generator state: keys, pos, has_gauss, cached


def search_state(es: Any) -> dict[str, Any]:
    """The state of ``es`` (a ``cma.CMAEvolutionStrategy`` whose ``randn`` option is a
    :class:`~.open_loop_es.NormalSource`) as tensors and plain numbers, by field path."""
    state: dict[str, Any] = {}
    for path, kind in FIELDS.items():
        value = _get(es, path)
        if value is None:
            state[path] = None
        elif kind.rstrip("?") in ("floats", "bools"):
            state[path] = [bool(v) if kind.startswith("bools") else float(v) for v in value]
        elif kind.rstrip("?") in ("float", "int"):
            state[path] = float(value) if kind.startswith("float") else int(value)
        elif kind.startswith("range"):
            state[path] = [value.start, value.stop] if isinstance(value, range) else [0, 0]
        elif kind == "rows":
            rows = np.array(value, dtype=np.float64).reshape(len(value), len(es.mean))
            state[path] = torch.from_numpy(rows)
        else:
            dtype = np.int64 if kind.startswith("index") else np.float64
            state[path] = torch.from_numpy(np.array(value, dtype=dtype))
    _, keys, pos, has_gauss, cached = es.opts["randn"].generator.get_state(legacy=True)
    state[_GENERATOR] = {
        "keys": torch.from_numpy(keys.astype(np.int64)),
        "pos": int(pos),
        "has_gauss": int(has_gauss),
        "cached_gaussian": float(cached),
    }
    return state


def restore_search_state(es: Any, state: Any) -> None:
    """Write ``state`` (from :func:`search_state`) into ``es``, a search cma's constructor
    has just built with the running run's options; ValueError (one line) if ``state`` is not
    the state of a search of ``es``'s dimension and population size. Nothing is written
    into ``es`` unless every value passes."""
    if not isinstance(state, dict):
        raise ValueError(f"the saved CMA-ES state is a {type(state).__name__}, not a dict")
    unknown = set(state) - set(FIELDS) - {_GENERATOR}
    missing = set(FIELDS) - set(state) | ({_GENERATOR} - set(state))
    if unknown or missing:
        named = sorted(unknown)[:3] if unknown else sorted(missing)[:3]
        what = "has fields a CMA-ES state has not" if unknown else "lacks fields"
        raise ValueError(f"the saved CMA-ES state {what}: {', '.join(map(str, named))}")
    n, popsize = len(es.mean), es.sp.popsize
    values = {path: _checked(path, kind, state[path], n, popsize) for path, kind in FIELDS.items()}
    generator = _checked_generator(state[_GENERATOR])
    for path, value in values.items():
        if value is not None or _has(es, path):  # not set yet: left as the constructor has it
            _set(es, path, value)
    for name, path in ALIASES.items():
        setattr(es, name, _get(es, path))
    es.opts["randn"].generator.set_state(generator)
    if es.countiter > 0:  # cma's first ask starts its wall-clock timer, later ones resume it
        from cma.utilities.utils import ElapsedWCTime

        es.timer = ElapsedWCTime()
        es.timer.pause()


def _checked(path: str, kind: str, value: Any, n: int, popsize: int) -> Any:
    """``value`` as the search keeps it, or ValueError naming ``path`` and what it accepts."""
    optional, kind = kind.endswith("?"), kind.rstrip("?")
    if value is None:
        if optional:
            return None
        raise ValueError(f"the saved CMA-ES state's {path} is missing (None)")
    if kind in ("float", "int"):
        accepted = (int,) if kind == "int" else (int, float)
        if type(value) not in accepted or math.isnan(value):
            raise ValueError(f"the saved CMA-ES state's {path} must be a number ({kind})")
        return float(value) if kind == "float" else value
    if kind in ("floats", "bools"):
        accepted = (bool,) if kind == "bools" else (int, float)
        if (
            not isinstance(value, list)
            or len(value) > MAX_HISTORY
            or not all(type(v) in accepted and v == v for v in value)  # v == v: not NaN
        ):
            raise ValueError(
                f"the saved CMA-ES state's {path} must be a list of at most {MAX_HISTORY:,} "
                f"{kind[:-1]}s"
            )
        return [float(v) for v in value] if kind == "floats" else list(value)
    if kind == "range":
        if not (
            isinstance(value, list)
            and len(value) == 2
            and all(type(v) is int and 0 <= v <= popsize for v in value)
        ):
            raise ValueError(
                f"the saved CMA-ES state's {path} must be [start, stop] in [0, {popsize}]"
            )
        return range(*value)
    shapes = {"n": (n,), "nn": (n, n), "ln": (popsize, n), "l": (popsize,), "index": (popsize,)}
    dtype = torch.int64 if kind == "index" else torch.float64
    if kind == "rows":  # at most popsize rows
        rows = value.shape[0] if isinstance(value, torch.Tensor) and value.ndim == 2 else -1
        shape, wanted = (rows, n), f"(at most {popsize}, {n})"
        fits = 0 <= rows <= popsize
    else:
        shape, wanted = shapes[kind], str(shapes[kind])
        fits = True
    if not (
        fits
        and isinstance(value, torch.Tensor)
        and value.dtype == dtype
        and tuple(value.shape) == shape
    ):
        raise ValueError(
            f"the saved CMA-ES state's {path} must be a {dtype} tensor of shape {wanted} "
            f"(a search of {n} parameters and {popsize} candidates)"
        )
    array = value.numpy().copy()
    if kind == "index" and not np.array_equal(np.sort(array), np.arange(popsize)):
        raise ValueError(f"the saved CMA-ES state's {path} is not an order of the candidates")
    if kind != "index" and np.isnan(array).any():
        raise ValueError(f"the saved CMA-ES state's {path} holds NaN")
    return list(array) if kind == "rows" else array


def _checked_generator(value: Any) -> tuple:
    """The normal source's generator state for ``RandomState.set_state``."""
    names = {"keys", "pos", "has_gauss", "cached_gaussian"}
    if not isinstance(value, dict) or set(value) != names:
        value = {}
    keys = value.get("keys")
    if (
        not value
        or not isinstance(keys, torch.Tensor)
        or keys.dtype != torch.int64
        or tuple(keys.shape) != (624,)
        or not bool(((keys >= 0) & (keys < 2**32)).all())
        or type(value["pos"]) is not int
        or not 0 <= value["pos"] <= 624
        or value["has_gauss"] not in (0, 1)
        or type(value["cached_gaussian"]) is not float
    ):
        raise ValueError(
            "the saved CMA-ES state's generator (randn) must be an MT19937 state: 624 keys in "
            "[0, 2**32), pos in [0, 624], has_gauss 0 or 1, a float cached_gaussian"
        )
    keys = keys.numpy().astype(np.uint32)
    return ("MT19937", keys, value["pos"], value["has_gauss"], value["cached_gaussian"])


def _get(root: Any, path: str) -> Any:
    for name in path.split("."):
        root = getattr(root, name, None)
    return root


def _has(root: Any, path: str) -> bool:
    *parents, name = path.split(".")
    parent = _get(root, ".".join(parents)) if parents else root
    return parent is not None and hasattr(parent, name)


def _set(root: Any, path: str, value: Any) -> None:
    *parents, name = path.split(".")
    for parent in parents:
        root = getattr(root, parent)
    setattr(root, name, value)
