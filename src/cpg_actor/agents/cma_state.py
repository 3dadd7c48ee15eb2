"""Saving and reading back a ``cma.CMAEvolutionStrategy`` without letting a checkpoint run code.

A CMA-ES object is pickled (``cma`` offers no other complete state), so reading one back must
not be an ordinary unpickling: a crafted pickle can name any importable callable, and protocol 4
follows dotted names (``cma`` + ``_np.f2py.subprocess.Popen`` reaches ``subprocess.Popen``).
:func:`load_search_state` reads with the pure-Python unpickler restricted at every opcode that
can reach code:

- a global is looked up only if its exact ``(module, name)`` pair is listed (no dotted names);
- REDUCE calls only numpy's and the builtins' reconstructors listed, never a class's constructor
  (cma's classes build log files and read option files when constructed);
- NEWOBJ makes only instances of the listed classes (``cls.__new__``, no ``__init__``), and
  BUILD fills in only instances of listed types (never a class or a function);
- the old protocol-0/1 instance opcodes are refused.

Then the object read back must be a CMAEvolutionStrategy whose options equal the running
search's own (the options are where cma keeps what it evaluates, calls or writes to disk); only
its random-number source (:class:`NormalSource`, carrying the generator state) is taken from
the file.
"""

from __future__ import annotations

import io
import math
import pickle
from typing import Any

import numpy as np
from numpy.random.bit_generator import BitGenerator

PICKLE_PROTOCOL = 4  # fixed, not the running Python's highest

# the classes a CMA-ES state is made of: NEWOBJ makes them, BUILD fills them in
_CMA_CLASSES = {
    ("cma.boundary_handler", "BoundNone"),
    ("cma.boundary_handler", "BoundTransform"),
    ("cma.evolution_strategy", "CMAEvolutionStrategy"),
    ("cma.evolution_strategy", "_CMASolutionDict_functional"),
    ("cma.evolution_strategy", "_CMAStopDict"),
    ("cma.evolution_strategy", "_StopTolXStagnation"),
    ("cma.logger", "CMADataLogger"),
    ("cma.optimization_tools", "BestSolution"),
    ("cma.options_parameters", "CMAOptions"),
    ("cma.options_parameters", "CMAParameters"),
    ("cma.recombination_weights", "RecombinationWeights"),
    ("cma.sampler", "GaussFullSampler"),
    ("cma.sigma_adaptation", "CMAAdaptSigmaCSA"),
    ("cma.transformations", "DiagonalDecoding"),
    ("cma.transformations", "GenoPheno"),
    ("cma.transformations", "RoundIntegerVariables"),
    ("cma.utilities.utils", "BlancClass"),
    ("cma.utilities.utils", "DictFromTagsInString"),
    ("cma.utilities.utils", "ElapsedWCTime"),
    ("cma.utilities.utils", "MoreToWrite"),
    ("cma.utilities.utils", "SolutionDict"),
    ("cpg_actor.agents.open_loop_es", "NormalSource"),
}
# what REDUCE may call: numpy's array, scalar, dtype and generator reconstructors (numpy 2 and
# 1 spell their module differently) and plain builtins
_RECONSTRUCTORS = {
    *(("builtins", name) for name in ("range", "slice", "set", "frozenset", "complex")),
    ("numpy", "dtype"),
    ("numpy.random._pickle", "__bit_generator_ctor"),
    ("numpy.random._pickle", "__randomstate_ctor"),
    *((f"numpy.{core}.multiarray", name)
      for core in ("_core", "core") for name in ("_reconstruct", "scalar")),
    *((f"numpy.{core}.numeric", "_frombuffer") for core in ("_core", "core")),
}  # fmt: skip
# objects the state holds by reference only (cma keeps these functions and classes as option
# values); never called or filled in by the unpickler
_REFERENCES = {
    ("cma.evolution_strategy", "_pass"),
    ("cma.options_parameters", "is_feasible"),
    ("numpy", "ndarray"),
    ("numpy.linalg", "eigh"),
    ("numpy.random._mt19937", "MT19937"),
}


class UnsafeState(pickle.UnpicklingError):
    """The saved bytes ask for something a CMA-ES state is not made of."""


class _Unpickler(pickle._Unpickler):
    """The pure-Python unpickler with the checks of the module docstring at each opcode."""

    dispatch = dict(pickle._Unpickler.dispatch)

    def __init__(self, data: bytes) -> None:
        super().__init__(io.BytesIO(data))
        self._classes: set[type] = set()  # filled as the listed classes are looked up
        self._reconstructors: set[int] = set()  # ids of the listed callables REDUCE may call

    def find_class(self, module: str, name: str) -> Any:
        pair = (module, name)
        if pair not in _CMA_CLASSES | _RECONSTRUCTORS | _REFERENCES:
            raise UnsafeState(f"it refers to {module}.{name}, which a CMA-ES state is not made of")
        found = super().find_class(module, name)
        if pair in _CMA_CLASSES:
            self._classes.add(found)
        elif pair in _RECONSTRUCTORS:
            self._reconstructors.add(id(found))
        return found

    def load_reduce(self) -> None:
        if id(self.stack[-2]) not in self._reconstructors:
            raise UnsafeState(f"it calls {self.stack[-2]!r}, which only numpy's reconstructors may")
        super().load_reduce()

    def load_newobj(self) -> None:
        self._check_class(self.stack[-2])
        super().load_newobj()

    def load_newobj_ex(self) -> None:
        self._check_class(self.stack[-3])
        super().load_newobj_ex()

    def load_build(self) -> None:
        target = self.stack[-2]
        if isinstance(target, type) or not (
            type(target) in self._classes
            or isinstance(target, (np.ndarray, np.dtype, np.random.RandomState, BitGenerator))
        ):
            raise UnsafeState(f"it fills in {type(target).__name__}, which is not part of a state")
        super().load_build()

    def load_refused(self) -> None:
        raise UnsafeState("it uses the old instance opcodes, which a CMA-ES state never does")

    def _check_class(self, cls: Any) -> None:
        if cls not in self._classes:
            raise UnsafeState(f"it makes a {cls!r}, which a CMA-ES state is not made of")

    dispatch[pickle.REDUCE[0]] = load_reduce
    dispatch[pickle.NEWOBJ[0]] = load_newobj
    dispatch[pickle.NEWOBJ_EX[0]] = load_newobj_ex
    dispatch[pickle.BUILD[0]] = load_build
    dispatch[pickle.INST[0]] = load_refused
    dispatch[pickle.OBJ[0]] = load_refused


def dump_search_state(es: Any) -> bytes:
    """The CMA-ES object as bytes for a checkpoint."""
    return pickle.dumps(es, protocol=PICKLE_PROTOCOL)


def load_search_state(data: bytes, running: Any) -> Any:
    """The CMA-ES object saved in ``data``, checked against ``running``, the search this run
    built from its own config; ValueError (one line) if the bytes are not a state this search
    can continue from."""
    import cma

    try:
        es = _Unpickler(data).load()
    except (pickle.UnpicklingError, AttributeError, ImportError, EOFError, TypeError) as error:
        raise ValueError(f"the saved CMA-ES state cannot be read: {error}") from None
    if type(es) is not cma.CMAEvolutionStrategy:
        raise ValueError(
            f"the saved CMA-ES state is a {type(es).__name__}, not a CMAEvolutionStrategy"
        )
    for options in _instances(es, cma.options_parameters.CMAOptions):
        _check_options(options, running.opts)
    return es


def _check_options(saved: Any, running: Any) -> None:
    """Every option as the running search has it, but for the random source's generator state."""
    from .open_loop_es import NormalSource

    if set(saved) != set(running):
        raise ValueError("the saved CMA-ES state has other options than this run's search")
    for key, value in running.items():
        kept = saved[key]
        if isinstance(value, NormalSource):
            same = type(kept) is NormalSource and type(kept.__dict__.get("generator")) is (
                np.random.RandomState
            )
        elif isinstance(value, float) and math.isnan(value):
            same = isinstance(kept, float) and math.isnan(kept)
        else:
            same = type(kept) is type(value) and _equal(kept, value)
        if not same:
            raise ValueError(f"the saved CMA-ES state's option {key!r} differs from this run's")


def _equal(a: Any, b: Any) -> bool:
    try:
        return bool(np.all(a == b)) if isinstance(a, np.ndarray) else bool(a == b)
    except (TypeError, ValueError):
        return False


def _instances(root: Any, kind: type) -> list[Any]:
    """Every object of type ``kind`` reachable from ``root`` through attributes, dict values,
    and list, tuple and set items (a state's options may be referenced from several places)."""
    found, seen, todo = [], set(), [root]
    while todo:
        item = todo.pop()
        if id(item) in seen or isinstance(item, (type, str, bytes, np.ndarray)):
            continue
        seen.add(id(item))
        if isinstance(item, kind):
            found.append(item)
        if isinstance(item, dict):
            todo.extend(item.values())
        elif isinstance(item, (list, tuple, set, frozenset)):
            todo.extend(item)
        if hasattr(item, "__dict__"):
            todo.extend(vars(item).values())
    return found
