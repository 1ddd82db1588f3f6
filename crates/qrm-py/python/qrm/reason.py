"""Qualitative reasoning over constraint networks: algebraic closure and scenarios.

A network is a list of constraints ``(A, B, C, [labels])``: the relation ``{A,B:C}`` is one of
the labels. Points are names (strings); labels are the calculus's.

>>> import qrm
>>> dc = qrm.Calculus.builtin("double-cross")
>>> r = qrm.reason.close(dc, [("A", "B", "C", ["left-front"]), ("B", "C", "D", ["left-front"])])
>>> r.consistent, r.constraints[("A", "B", "D")]
(True, ['left-front', 'left-middle', 'left-back'])

Binary calculi (OPRA-m, STAR-m) close networks of pairs ``(A, B, [labels])``:

>>> opra = qrm.BinaryCalculus.builtin("opra-1")
>>> r = qrm.reason.close_binary(opra, [("A", "B", ["0_0"]), ("B", "C", ["0_0"])])
>>> r.consistent, r.constraints[("A", "C")]
(True, ['0_2', '2_0', 's_0'])

Any binary calculus GQR or SparQ defines is an `Algebra` read from its files (RCC-8, Allen's
interval algebra, the point algebra, cardinal directions, ...), closed and solved the same way;
GQR's ``.csp`` networks are read by `read_csp`:

>>> pa = qrm.reason.Algebra.from_gqr_tables(
...     "point", "< :: >\\n= :: =\\n> :: <\\n",
...     "< : < :: ( < )\\n< : = :: ( < )\\n< : > :: ( < = > )\\n"
...     "= : < :: ( < )\\n= : = :: ( = )\\n= : > :: ( > )\\n"
...     "> : < :: ( < = > )\\n> : = :: ( > )\\n> : > :: ( > )\\n", "=")
>>> [(name, len(c)) for name, c in qrm.reason.read_csp(pa, "2 #chain\\n0 1 ( < )\\n1 2 ( < )\\n.\\n")]
[('chain', 2)]
>>> qrm.reason.close_binary(pa, [("a", "b", ["<"]), ("b", "c", ["<"])]).constraints[("a", "c")]
['<']
>>> qrm.reason.consistency(pa, [("a", "b", ["<", "="]), ("b", "a", ["<", "="])]).status
'consistent'

Probabilistic reasoning over maps lives on the map: ``Pqrm.infer`` and ``Pqrm.check``.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Dict, Iterable, List, Optional, Sequence, Tuple, Union

from . import _qrm
from ._qrm import BinaryAlgebra, BinaryCalculus, Calculus

Algebra = BinaryAlgebra
"""A binary calculus's tables: ``Algebra.from_gqr("rcc8.spec")``, ``Algebra.from_sparq(path)``,
``Algebra.of(BinaryCalculus.builtin("opra-2"))``; ``laws()`` says which relation-algebra laws
they obey."""

__all__ = [
    "Algebra",
    "BinaryClosure",
    "BinarySolution",
    "Closure",
    "Pair",
    "Triplet",
    "close",
    "close_binary",
    "consistency",
    "read_csp",
    "scenario",
]

Triplet = Tuple[str, str, str]
Pair = Tuple[str, str]


@dataclass(frozen=True)
class Closure:
    """The result of `close` or `scenario`."""

    consistent: bool
    """False when closure emptied a constraint (or, for `scenario`, when none exists)."""
    constraints: Dict[Triplet, List[str]]
    """Every ordered triplet of distinct points with its labels (empty dict for a scenario
    search that found none)."""
    explanation: Optional[str] = None
    """Why closure found the network inconsistent (the chain of refinements)."""


def _network(constraints: Iterable[Tuple[str, str, str, Sequence[str]]]) -> str:
    rows = []
    for c in constraints:
        a, b, d, labels = c
        rows.append([str(a), str(b), str(d), [str(x) for x in labels]])
    return json.dumps({"constraints": rows})


def _triplets(rows: Optional[List[List[object]]]) -> Dict[Triplet, List[str]]:
    out: Dict[Triplet, List[str]] = {}
    for a, b, c, labels in rows or []:
        assert isinstance(labels, list)
        out[(str(a), str(b), str(c))] = [str(x) for x in labels]
    return out


def close(
    calculus: Calculus,
    constraints: Iterable[Tuple[str, str, str, Sequence[str]]],
    *,
    general_position: bool = False,
) -> Closure:
    """Algebraic closure (SparQ semantics) with the calculus's sound tables, or the tables of
    configurations in general position with ``general_position=True``."""
    out = json.loads(
        _qrm.reason_close(calculus, _network(constraints), general_position=general_position)
    )
    return Closure(out["consistent"], _triplets(out["constraints"]), out["explanation"])


def scenario(
    calculus: Calculus,
    constraints: Iterable[Tuple[str, str, str, Sequence[str]]],
    *,
    general_position: bool = False,
    max_nodes: int = 100_000,
) -> Closure:
    """One algebraically closed scenario refining the network (every triplet one label), or
    ``consistent=False`` when there is none."""
    out = json.loads(
        _qrm.reason_scenario(
            calculus,
            _network(constraints),
            general_position=general_position,
            max_nodes=max_nodes,
        )
    )
    return Closure(out["consistent"], _triplets(out["constraints"]))


@dataclass(frozen=True)
class BinaryClosure:
    """The result of `close_binary`."""

    consistent: bool
    """False when closure emptied a relation."""
    constraints: Dict[Pair, List[str]]
    """Every pair ``(A, B)`` listed with ``A`` before ``B`` whose relation is not universal."""
    explanation: Optional[str] = None
    """Which three points could not agree, when inconsistent."""


def close_binary(
    calculus: Union[BinaryCalculus, BinaryAlgebra],
    constraints: Iterable[Tuple[str, str, Sequence[str]]],
) -> BinaryClosure:
    """Algebraic closure (path consistency, as GQR runs it) of a binary network;
    ``(A, B, labels)`` says the relation of B as seen from A is one of ``labels``."""
    rows = [(str(a), str(b), [str(x) for x in labels]) for a, b, labels in constraints]
    out = json.loads(_qrm.reason_close_binary(calculus, rows))
    pairs: Dict[Pair, List[str]] = {
        (str(a), str(b)): [str(x) for x in labels] for a, b, labels in out["constraints"]
    }
    return BinaryClosure(out["consistent"], pairs, out["explanation"])


def _pairs(rows: Optional[List[List[object]]]) -> Dict[Pair, List[str]]:
    out: Dict[Pair, List[str]] = {}
    for a, b, labels in rows or []:
        assert isinstance(labels, list)
        out[(str(a), str(b))] = [str(x) for x in labels]
    return out


@dataclass(frozen=True)
class BinarySolution:
    """The result of `consistency`."""

    status: str
    """``"consistent"``, ``"inconsistent"``, or ``"unknown"`` when the node budget ran out."""
    constraints: Dict[Pair, List[str]]
    """The scenario found (one relation per pair), else empty."""
    nodes: int
    """Search nodes used."""


def consistency(
    calculus: Union[BinaryCalculus, BinaryAlgebra],
    constraints: Iterable[Tuple[str, str, Sequence[str]]],
    *,
    max_nodes: int = 1_000_000,
    split: Union[str, "os.PathLike[str]", Sequence[Sequence[str]], None] = None,
    restarts: bool = True,
) -> BinarySolution:
    """Consistency by backtracking search with path consistency at every node (GQR's
    ``consistency``): a path-consistent refinement whose every constraint is a split, none,
    or ``"unknown"`` when ``max_nodes`` decisions did not decide it.

    ``split``: the relations to split constraints into — a GQR cover-set file (such as
    ``data/rcc8/calculus/hornalg``, GQR's ``-c horn``) or its members as label lists; by
    default base relations, and a solution is atomic. ``restarts=False`` is GQR's ``--2w``."""
    rows = [(str(a), str(b), [str(x) for x in labels]) for a, b, labels in constraints]
    if split is None:
        out = json.loads(
            _qrm.reason_solve_binary(calculus, rows, max_nodes=max_nodes, restarts=restarts)
        )
    elif isinstance(split, (str, os.PathLike)):
        out = json.loads(
            _qrm.reason_solve_binary(
                calculus, rows, max_nodes=max_nodes, split_path=os.fspath(split), restarts=restarts
            )
        )
    else:
        sets = [[str(x) for x in member] for member in split]
        out = json.loads(
            _qrm.reason_solve_binary(
                calculus, rows, max_nodes=max_nodes, split_sets=sets, restarts=restarts
            )
        )
    return BinarySolution(str(out["status"]), _pairs(out["constraints"]), int(out["nodes"]))


def read_csp(
    calculus: Union[BinaryCalculus, BinaryAlgebra], text: str
) -> List[Tuple[str, List[Tuple[str, str, List[str]]]]]:
    """The networks of a GQR ``.csp`` text, each ``(name, [(A, B, labels), ...])`` with points
    named ``"0"``, ``"1"``, ... (a pair listed once, not universal)."""
    nets = json.loads(_qrm.reason_read_csp(calculus, text))
    return [
        (
            str(n["name"]),
            [(str(a), str(b), [str(x) for x in labels]) for a, b, labels in n["constraints"]],
        )
        for n in nets
    ]
