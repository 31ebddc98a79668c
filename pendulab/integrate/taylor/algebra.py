"""Symbolic algebra of the CasADi -> heyoka translation: parameter coefficients, monomials, the graph walker.

See :mod:`pendulab.integrate.taylor` for what the simplifications are and why.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

# -- CasADi SX graph -> heyoka expressions ----------------------------------------
_OP_NAMES = {getattr(ca, n): n for n in dir(ca) if n.startswith("OP_")}

#: Unary functions: CasADi function (parameter-only values), NumPy function (sample values),
#: heyoka function name (state-dependent values; None: not supported there) and cost in convolutions.
_UNARY: dict[int, tuple[Callable[[Any], Any], Callable[[np.ndarray], np.ndarray], str | None, float]] = {
    ca.OP_SQRT: (ca.sqrt, np.sqrt, "sqrt", 1.0),
    ca.OP_SIN: (ca.sin, np.sin, "sin", 1.0),
    ca.OP_COS: (ca.cos, np.cos, "cos", 1.0),
    ca.OP_TAN: (ca.tan, np.tan, "tan", 2.0),
    ca.OP_EXP: (ca.exp, np.exp, "exp", 1.0),
    ca.OP_LOG: (ca.log, np.log, "log", 1.0),
    ca.OP_ASIN: (ca.asin, np.arcsin, "asin", 2.0),
    ca.OP_ACOS: (ca.acos, np.arccos, "acos", 2.0),
    ca.OP_ATAN: (ca.atan, np.arctan, "atan", 2.0),
    ca.OP_SINH: (ca.sinh, np.sinh, "sinh", 1.0),
    ca.OP_COSH: (ca.cosh, np.cosh, "cosh", 1.0),
    ca.OP_TANH: (ca.tanh, np.tanh, "tanh", 2.0),
    ca.OP_ASINH: (ca.asinh, np.arcsinh, "asinh", 2.0),
    ca.OP_ACOSH: (ca.acosh, np.arccosh, "acosh", 2.0),
    ca.OP_ATANH: (ca.atanh, np.arctanh, "atanh", 2.0),
    ca.OP_LOG1P: (ca.log1p, np.log1p, "log1p", 1.0),
    ca.OP_EXPM1: (ca.expm1, np.expm1, "expm1", 1.0),
    ca.OP_FABS: (ca.fabs, np.abs, None, 0.0),
    ca.OP_ERF: (ca.erf, None, "erf", 2.0),
}
_ARITH_UNARY = {ca.OP_ASSIGN, ca.OP_NEG, ca.OP_TWICE, ca.OP_SQ, ca.OP_INV}
_ARITH_BINARY = {ca.OP_ADD, ca.OP_SUB, ca.OP_MUL, ca.OP_DIV, ca.OP_POW, ca.OP_CONSTPOW, ca.OP_ATAN2}
_OTHER_TRIG = {"sin": "cos", "cos": "sin"}

#: Parameter points at which coefficient identities are tested, and the relative threshold.
_N_SAMPLES = 3
_REL = 1e-11
#: A monomial times a sum is expanded when the result has at most this many terms.
_EXPAND_LIMIT = 16
#: Cost estimate of the compiled Taylor step: a product, quotient or elementary function of two
#: series is a convolution (O(order) per Taylor order); sums and scalings are linear (O(1)).
_CONV, _LINEAR = 1.0, 0.1


class _Coef:
    """A coefficient that depends on the parameters only.

    ``sx`` is its CasADi expression in ``p``; ``v`` its values at :data:`_N_SAMPLES` random
    parameter points and ``mag`` a rounding scale of ``v`` (the same expression evaluated
    with absolute values). Two coefficients are identical when their difference is below
    ``_REL * mag`` at every sample point: a non-zero algebraic function of the parameters
    does not vanish to 1e-11 at three random points (Schwartz-Zippel).
    """

    __slots__ = ("sx", "v", "mag")

    def __init__(self, sx: Any, v: np.ndarray, mag: np.ndarray) -> None:
        self.sx, self.v, self.mag = sx, v, mag

    @classmethod
    def const(cls, c: float) -> _Coef:
        return cls(ca.SX(c), np.full(_N_SAMPLES, float(c)), np.full(_N_SAMPLES, abs(float(c))))

    def __add__(self, o: _Coef) -> _Coef:
        return _Coef(self.sx + o.sx, self.v + o.v, self.mag + o.mag)

    def __sub__(self, o: _Coef) -> _Coef:
        return _Coef(self.sx - o.sx, self.v - o.v, self.mag + o.mag)

    def __mul__(self, o: _Coef) -> _Coef:
        return _Coef(self.sx * o.sx, self.v * o.v, self.mag * o.mag)

    def __truediv__(self, o: _Coef) -> _Coef:
        with np.errstate(all="ignore"):
            return _Coef(self.sx / o.sx, self.v / o.v, self.mag / np.abs(o.v))

    def __neg__(self) -> _Coef:
        return _Coef(-self.sx, -self.v, self.mag)

    def apply(self, sx_fn: Callable[..., Any], np_fn: Callable[..., np.ndarray] | None, *others: _Coef) -> _Coef:
        """A function of parameter-only values (NaN samples when NumPy has no counterpart)."""
        with np.errstate(all="ignore"):
            v = np_fn(self.v, *(o.v for o in others)) if np_fn is not None else np.full(_N_SAMPLES, np.nan)
        return _Coef(sx_fn(self.sx, *(o.sx for o in others)), v, np.abs(v))

    def is_zero(self) -> bool:
        return bool(self.sx.is_zero() or np.all(np.abs(self.v) <= _REL * self.mag))

    def ratio(self, o: _Coef) -> float | None:
        """``r`` with ``self == r * o`` identically for a small rational ``r`` (|num|, den <= 12), else None."""
        if not np.all(np.isfinite(self.v)) or not np.all(np.isfinite(o.v)) or o.v[0] == 0.0:
            return None
        r0 = self.v[0] / o.v[0]
        for den in range(1, 13):
            num = round(r0 * den)
            r = num / den
            if num != 0 and abs(num) <= 12 and np.all(np.abs(self.v - r * o.v) <= _REL * (self.mag + abs(r) * o.mag)):
                return r
        return None

    def key(self) -> bytes:
        return self.v.tobytes()


_ONE = _Coef.const(1.0)

# A value during the walk is a linear combination {monomial: _Coef}: a monomial is a sorted
# tuple of atom ids (state-dependent factors; () is the constant monomial); {} is zero.
_Lin = dict


def _op_name(op: int) -> str:
    return _OP_NAMES.get(op, f"operation id {op}").removeprefix("OP_").lower()


def _sorted_items(a: _Lin) -> list[tuple[tuple[int, ...], _Coef]]:
    return sorted(a.items(), key=lambda kv: (len(kv[0]), kv[0]))


@dataclass(frozen=True)
class _Strategy:
    """How products and quotients are rebuilt; :func:`translate` keeps the cheapest result.

    expand : {"all", "trig", "none"}
        Which monomial x sum products are expanded (all, those whose monomial holds a sine
        or cosine, none). Expanding exposes cancellations and trigonometric identities;
        it also duplicates shared sums.
    reciprocal : bool
        ``a / b`` as ``a`` times the reciprocal of each factor of ``b`` (it expands like a
        product and cancels against that factor) rather than one quotient atom per use.
    """

    expand: str
    reciprocal: bool


_STRATEGIES = (_Strategy("all", True), _Strategy("trig", False), _Strategy("none", False))


class _Builder:
    """Walks one SX Function; keeps the atoms, hoisted coefficients and a cost estimate."""

    def __init__(self, hy: Any, par_offset: int, strategy: _Strategy, params: Sequence[_Coef] = ()) -> None:
        self.hy = hy
        self.par_offset = par_offset
        self.strategy = strategy
        self.params = tuple(params)  # the model parameters as coefficients (offsets recognised by _offsets)
        self.atoms: list[Any] = []  # id -> heyoka expression (a factor that is not a product)
        self.atom_ids: dict[Any, int] = {}
        # Sines and cosines are keyed by their angle as a canonical linear combination (not by the heyoka
        # expression of the argument): the angle-sum identities build angles such as (a - b) - a + a, which
        # must be the atom of a - b, and cos(0), sin(-a) must not become atoms of their own.
        self.trig: dict[int, tuple[str, tuple]] = {}  # atom id -> ("sin"|"cos", angle key)
        self.trig_ids: dict[tuple[str, tuple], int] = {}
        self.angles: dict[tuple, _Lin] = {}  # angle key -> angle (normalised sign)
        self.inputs: set[int] = set()  # ids of the input atoms (runtime parameters par[0:nu])
        # Reciprocals: atom id <-> id of its reciprocal atom (both ways). A monomial may hold both
        # (Laurent monomials); the pair cancels when monomials multiply (``r * (x / r) = x``).
        self.inverse: dict[int, int] = {}
        self.reciprocals: set[int] = set()  # ids of the reciprocal atoms (never emitted on their own)
        self.coefs: list[_Coef] = []  # hoisted coefficient k -> par[par_offset + k]
        self.mono_cache: dict[tuple[int, ...], Any] = {}
        self.lin_cache: dict[tuple, Any] = {}
        self.nodes: dict[int, tuple[Any, float, tuple[Any, ...]]] = {}  # id(expr) -> (expr, cost, children)

    # -- expression nodes and their cost ---------------------------------------------
    def node(self, expr: Any, cost: float, *children: Any) -> Any:
        if id(expr) not in self.nodes:
            self.nodes[id(expr)] = (expr, cost, children)
        return expr

    def cost(self, roots: Sequence[Any]) -> float:
        """Estimated cost of one Taylor step: convolutions plus a tenth of the linear operations."""
        seen: set[int] = set()
        stack = list(roots)
        total = 0.0
        while stack:
            e = stack.pop()
            if id(e) in seen or id(e) not in self.nodes:
                continue
            seen.add(id(e))
            _, c, children = self.nodes[id(e)]
            total += c
            stack.extend(children)
        return total

    def mul_expr(self, x: Any, y: Any, cost: float = _CONV) -> Any:
        return self.node(x * y, cost, x, y)

    # -- leaves ---------------------------------------------------------------
    def atom(self, expr: Any) -> int:
        if expr not in self.atom_ids:
            self.atom_ids[expr] = len(self.atoms)
            self.atoms.append(expr)
        return self.atom_ids[expr]

    def input_atom(self, i: int) -> int:
        """The atom of input ``u[i]``, the runtime parameter ``par[i]``."""
        f = self.atom(self.hy.par[i])
        self.inputs.add(f)
        return f

    def trig_atom(self, name: str, angle: _Lin) -> _Lin:
        """``sin`` or ``cos`` of a state-dependent or zero ``angle``, as a linear combination.

        The angle is brought to a canonical sign (its first monomial's coefficient positive; then
        ``sin(-a) = -sin(a)``, ``cos(-a) = cos(a)``) and keyed by its monomials and coefficient values,
        so equal angles built in different ways share one atom (one sine/cosine pair in heyoka).
        """
        if self.param_only(angle):
            sx_fn, np_fn = (ca.sin, np.sin) if name == "sin" else (ca.cos, np.cos)
            return self.lin(self.value(angle).apply(sx_fn, np_fn))
        items = _sorted_items(angle)
        lead = next(c for m, c in items if m)
        sign = 1.0
        if lead.v[0] < 0.0:
            angle = self.scale(angle, _Coef.const(-1.0))
            items = _sorted_items(angle)
            sign = -1.0 if name == "sin" else 1.0
        akey = tuple((m, c.key()) for m, c in items)
        self.angles.setdefault(akey, angle)
        key = (name, akey)
        if key not in self.trig_ids:
            arg = self.materialize(angle)
            i = self.atom(self.node(getattr(self.hy, name)(arg), _CONV, arg))
            self.trig[i] = key
            self.trig_ids[key] = i
        return {(self.trig_ids[key],): _Coef.const(sign)}

    def coef_expr(self, c: _Coef) -> Any:
        """A coefficient as a heyoka leaf: a number, or a hoisted runtime parameter (shared when identical).

        An opposite coefficient gets a parameter of its own: heyoka takes ``-par`` for a series, so
        ``(-par) * x`` would be a product of two series (O(order^2) per step) instead of a scaling.
        """
        if c.sx.is_constant():
            return self.hy.expression(float(c.sx))
        for k, old in enumerate(self.coefs):
            if c.ratio(old) == 1.0:
                return self.hy.par[self.par_offset + k]
        self.coefs.append(c)
        return self.hy.par[self.par_offset + len(self.coefs) - 1]

    # -- heyoka expressions of monomials and linear combinations ---------------------
    def monomial(self, mono: tuple[int, ...]) -> Any:
        """A monomial as one heyoka expression: the product of its atoms over the product of its reciprocals' atoms.

        heyoka rewrites ``x * (1 / y)`` as ``x / y``, so a reciprocal atom costs one division wherever it
        multiplies; dividing once by the whole denominator costs one division per monomial.
        """
        if mono not in self.mono_cache:
            num = tuple(f for f in mono if f not in self.reciprocals)
            den = tuple(sorted(self.inverse[f] for f in mono if f in self.reciprocals))
            if not den:
                self.mono_cache[mono] = self._product(num)
            else:
                top, bottom = self._product(num) if num else self.hy.expression(1.0), self._product(den)
                self.mono_cache[mono] = self.node(top / bottom, _CONV, top, bottom)
        return self.mono_cache[mono]

    def _product(self, mono: tuple[int, ...]) -> Any:
        """A product of (non-reciprocal) atoms, ``mono`` sorted and non-empty."""
        if mono not in self.mono_cache:
            # Left fold in sorted order (heyoka's CSE shares common prefixes); x*x for squares.
            out = None
            i = 0
            while i < len(mono):
                j = i
                while j < len(mono) and mono[j] == mono[i]:
                    j += 1
                base = self.atoms[mono[i]]
                n = j - i
                factor = base if n == 1 else self.mul_expr(base, base) if n == 2 else self.node(base ** float(n), _CONV, base)
                out = factor if out is None else self.mul_expr(out, factor)
                i = j
            self.mono_cache[mono] = out
        return self.mono_cache[mono]

    def term(self, mono: tuple[int, ...], c: _Coef) -> Any:
        if not mono:
            return self.coef_expr(c)
        if all(f in self.reciprocals for f in mono) and not (c.sx.is_one() or c.sx.is_minus_one()):
            # c / d rather than c * (1 / d): heyoka would make the latter two operations.
            den = self._product(tuple(sorted(self.inverse[f] for f in mono)))
            top = self.coef_expr(c)
            return self.node(top / den, _CONV, top, den)
        m = self.monomial(mono)
        if c.sx.is_one():
            return m
        if c.sx.is_minus_one():
            return self.node(-m, _LINEAR, m)
        return self.mul_expr(self.coef_expr(c), m, _LINEAR)

    def sum_expr(self, terms: list[Any]) -> Any:
        return terms[0] if len(terms) == 1 else self.node(self.hy.sum(terms), _LINEAR * (len(terms) - 1), *terms)

    def materialize(self, a: _Lin) -> Any:
        """A linear combination as one heyoka expression, common factors pulled out greedily."""
        if not a:
            return self.hy.expression(0.0)
        items = _sorted_items(a)
        key = tuple((m, c.key()) for m, c in items)
        if key not in self.lin_cache:
            self.lin_cache[key] = self._factor(items)
        return self.lin_cache[key]

    def _offsets(self, items: list[tuple[tuple[int, ...], _Coef]]) -> list[tuple[tuple[int, ...], _Coef]]:
        """``a + b x -> b (x + r p)`` when ``a / b`` is identically a small rational ``r`` times a parameter ``p``.

        Hoisting makes a spring force ``k (r - L)`` the sum ``k r - k L`` of two large numbers, whose
        difference loses digits (and costs two operations); ``x - L`` is exact near rest length and one
        shared atom. ``x`` is a single atom, ``a`` the constant term, ``b`` not a number (a numeric ``b`` gains nothing).
        """
        const = next((c for m, c in items if not m), None)
        if const is None or const.sx.is_constant() or not self.params:
            return items
        for k, (m, b) in enumerate(items):
            if len(m) != 1 or m[0] in self.reciprocals or b.sx.is_constant():
                continue
            q = const / b
            for par in self.params:
                r = q.ratio(par)
                if r is not None:
                    # The offset's coefficient is r * p itself (exact), not the rounded quotient a / b.
                    shifted = self.materialize({m: _ONE, (): _Coef.const(r) * par})
                    out = {mi: c for i, (mi, c) in enumerate(items) if i != k and mi}
                    self.accumulate(out, (self.atom(shifted),), b)
                    return _sorted_items(out)
        return items

    def _factor(self, items: list[tuple[tuple[int, ...], _Coef]]) -> Any:
        items = self._offsets(items)
        # A common coefficient (up to small rational ratios): c * (sum of r_i m_i).
        if len(items) > 1 and not all(c.sx.is_constant() for _, c in items):
            c0 = items[-1][1]
            ratios = [c.ratio(c0) for _, c in items]
            if all(r is not None for r in ratios):
                inner = self._factor([(m, _Coef.const(r)) for (m, _), r in zip(items, ratios, strict=True)])
                return self.mul_expr(self.coef_expr(c0), inner, _LINEAR)
        # Greedy Horner: the atom shared by most terms, M1 f + M2 f + R -> f (M1 + M2) + R.
        counts: dict[int, int] = {}
        for m, _ in items:
            for f in set(m):
                counts[f] = counts.get(f, 0) + 1
        # Ties go to a state-dependent atom: pulling out an input (a runtime parameter) saves a
        # scaling, pulling out a state-dependent factor saves a product or a division.
        best = max(counts, key=lambda f: (counts[f], f not in self.inputs, -f), default=None)
        if best is not None and counts[best] > 1:
            inside, outside = [], []
            for m, c in items:
                if best in m:
                    k = m.index(best)
                    inside.append((m[:k] + m[k + 1 :], c))
                else:
                    outside.append((m, c))
            inner = self._factor(inside)
            if best in self.reciprocals:  # (sum) / d: one division, whatever the sum
                orig = self.atoms[self.inverse[best]]
                product = self.node(inner / orig, _CONV, inner, orig)
            else:
                product = self.mul_expr(self.atoms[best], inner, _CONV if any(m for m, _ in inside) else _LINEAR)
            return product if not outside else self.sum_expr([product, self._factor(outside)])
        return self.sum_expr([self.term(m, c) for m, c in items])

    def as_term(self, a: _Lin) -> tuple[tuple[int, ...], _Coef]:
        """``a`` as one coefficient times one monomial; a sum becomes an atom, its common coefficient factored out."""
        if len(a) == 1:
            ((m, c),) = a.items()
            return m, c
        items = _sorted_items(a)
        c0 = items[-1][1]
        ratios = [c.ratio(c0) for _, c in items]
        if all(r is not None for r in ratios):
            scaled = {m: _Coef.const(r) for (m, _), r in zip(items, ratios, strict=True)}
            return (self.atom(self.materialize(scaled)),), c0
        return (self.atom(self.materialize(a)),), _ONE

    # -- arithmetic on linear combinations ------------------------------------------------
    @staticmethod
    def param_only(a: _Lin) -> bool:
        return all(not m for m in a)

    @staticmethod
    def value(a: _Lin) -> _Coef:
        return a.get((), _Coef.const(0.0))

    @staticmethod
    def lin(c: _Coef) -> _Lin:
        return {} if c.is_zero() else {(): c}

    @staticmethod
    def single(m: tuple[int, ...], c: _Coef) -> _Lin:
        return {} if c.is_zero() else {m: c}

    @staticmethod
    def scale(a: _Lin, c: _Coef) -> _Lin:
        out = {}
        for m, v in a.items():
            w = v * c
            if not w.is_zero():
                out[m] = w
        return out

    @staticmethod
    def accumulate(out: _Lin, m: tuple[int, ...], c: _Coef) -> None:
        w = out[m] + c if m in out else c
        if w.is_zero():
            out.pop(m, None)
        else:
            out[m] = w

    def add(self, a: _Lin, b: _Lin, sign: float = 1.0) -> _Lin:
        out = dict(a)
        for m, v in b.items():
            self.accumulate(out, m, v if sign > 0 else -v)
        return self.fold_trig(out)

    def fold_trig(self, a: _Lin) -> _Lin:
        """Apply sin^2 + cos^2 = 1 and the angle-sum identities to pairs of terms, in place.

        With M any monomial and c a coefficient: ``c M s_a^2 + c M c_a^2 -> c M``,
        ``c M (c_a c_b +- s_a s_b) -> c M cos(a -+ b)``, ``c M (s_a c_b -+ c_a s_b) -> c M sin(a -+ b)``.
        """
        if not self.trig or len(a) < 2:
            return a
        changed = True
        while changed:
            changed = False
            for m, c in list(a.items()):
                if m in a and any(self._fold_pair(a, m, c, i, j) for i, j in self._trig_pairs(m)):
                    changed = True
                    break
        return a

    def _trig_pairs(self, m: tuple[int, ...]) -> list[tuple[int, int]]:
        idx = [k for k, f in enumerate(m) if f in self.trig]
        return [(i, j) for n, i in enumerate(idx) for j in idx[n + 1 :] if m[i] != m[j] or j == i + 1]

    def _fold_pair(self, a: _Lin, m: tuple[int, ...], c: _Coef, i: int, j: int) -> bool:
        (fa, xa), (fb, xb) = self.trig[m[i]], self.trig[m[j]]
        pa = self.trig_ids.get((_OTHER_TRIG[fa], xa))
        pb = self.trig_ids.get((_OTHER_TRIG[fb], xb))
        if pa is None or pb is None:
            return False
        rest = m[:i] + m[i + 1 : j] + m[j + 1 :]
        partner = tuple(sorted((*rest, pa, pb)))
        if partner == m or partner not in a:
            return False
        cp = a[partner]
        r = cp.ratio(c)
        if r not in (1.0, -1.0):
            return False
        if xa == xb:  # m and partner are s_a s_a and c_a c_a
            if r != 1.0:
                return False
            del a[m], a[partner]
            self.accumulate(a, rest, c)
            return True
        angle_a, angle_b = self.angles[xa], self.angles[xb]
        if fa == fb:  # c_cos c_a c_b + c_sin s_a s_b with c_sin = r c_cos: c_cos cos(a - r b)
            new, coef = self.trig_atom("cos", self._angle_sum(angle_a, angle_b, -r)), (c if fa == "cos" else cp)
        else:  # c s_u c_w + r c c_u s_w = c sin(u + r w)
            u, w = (angle_a, angle_b) if fa == "sin" else (angle_b, angle_a)
            new, coef = self.trig_atom("sin", self._angle_sum(u, w, r)), c
        del a[m], a[partner]
        for mt, ct in new.items():  # one trig atom (or a constant when the angle vanishes)
            self.accumulate(a, tuple(sorted((*rest, *mt))), coef * ct)
        return True

    def _angle_sum(self, x: _Lin, y: _Lin, sign: float) -> _Lin:
        """``x + sign * y`` for angles (plain sum: no trigonometric folding inside an argument)."""
        out = dict(x)
        for m, v in y.items():
            self.accumulate(out, m, v if sign > 0 else -v)
        return out

    def join(self, ma: tuple[int, ...], mb: tuple[int, ...]) -> tuple[int, ...]:
        """The monomial ``ma * mb``: sorted, each atom cancelled against its reciprocal (``r * (1 / r) = 1``)."""
        m = tuple(sorted(ma + mb))
        if not self.reciprocals or not any(f in self.reciprocals for f in m):
            return m
        out = list(m)
        for f in set(m) & self.reciprocals:
            for _ in range(min(out.count(f), out.count(self.inverse[f]))):
                out.remove(f)
                out.remove(self.inverse[f])
        return tuple(out)

    def reciprocal(self, f: int) -> int:
        """The atom ``1 / f`` (``f`` itself when ``f`` is a reciprocal's: ``1 / (1 / x) = x``)."""
        if f not in self.inverse:
            # Never emitted on its own (monomial, term and _factor divide by the atom instead): no cost.
            i = self.atom(self.node(self.hy.expression(1.0) / self.atoms[f], 0.0))
            self.inverse[f], self.inverse[i] = i, f
            self.reciprocals.add(i)
        return self.inverse[f]

    def mul(self, a: _Lin, b: _Lin) -> _Lin:
        if not a or not b:
            return {}
        if self.param_only(a):
            return self.scale(b, self.value(a))
        if self.param_only(b):
            return self.scale(a, self.value(b))
        if self._expand(a, b):
            # Cancellations and trigonometric identities show up only between monomials.
            out: _Lin = {}
            for ma, c_a in a.items():
                for mb, c_b in b.items():
                    self.accumulate(out, self.join(ma, mb), c_a * c_b)
            return self.fold_trig(out)
        ma, c_a = self.as_term(a)
        mb, c_b = self.as_term(b)
        return self.single(self.join(ma, mb), c_a * c_b)

    def _expand(self, a: _Lin, b: _Lin) -> bool:
        small, big = (a, b) if len(a) <= len(b) else (b, a)
        if self.strategy.expand == "none" or len(small) > 1 or len(big) > _EXPAND_LIMIT:
            return False
        return self.strategy.expand == "all" or any(f in self.trig for m in small for f in m)

    def div(self, a: _Lin, b: _Lin) -> _Lin:
        if not b:
            raise ZeroDivisionError("translate: division by a structural zero in the CasADi graph")
        if self.param_only(b):
            return self.scale(a, _ONE / self.value(b))
        if a == b:
            return {(): _ONE}
        mb, c_b = self.as_term(b)
        if self.strategy.reciprocal:
            # One reciprocal atom per factor of the denominator, so that it cancels against that factor.
            return self.mul(a, {tuple(sorted(self.reciprocal(f) for f in mb)): _ONE / c_b})
        den = self.monomial(mb)
        num, c_a = ((), self.value(a)) if self.param_only(a) else self.as_term(a)
        top = self.monomial(num) if num else self.hy.expression(1.0)
        return self.single((self.atom(self.node(top / den, _CONV, top, den)),), c_a / c_b)

    def unary(self, op: int, a: _Lin) -> _Lin:
        sx_fn, np_fn, name, cost = _UNARY[op]
        if self.param_only(a):
            return self.lin(self.value(a).apply(sx_fn, np_fn))
        if name is None:
            raise NotImplementedError(
                f"translate: CasADi operation {_op_name(op)!r} of a state-dependent value has no heyoka counterpart"
            )
        if name in _OTHER_TRIG:
            return self.trig_atom(name, a)
        arg = self.materialize(a)
        return {(self.atom(self.node(getattr(self.hy, name)(arg), cost * _CONV, arg)),): _ONE}

    def power(self, a: _Lin, b: _Lin) -> _Lin:
        if self.param_only(a) and self.param_only(b):
            return self.lin(self.value(a).apply(lambda x, y: x**y, np.power, self.value(b)))
        if self.param_only(b) and self.value(b).sx.is_constant():
            n = float(self.value(b).sx)
            if n == 0.0:
                return {(): _ONE}
            if n == int(n) and 1 <= n <= 4:
                out = a
                for _ in range(int(n) - 1):
                    out = self.mul(out, a)
                return out
        base = self.materialize(a)
        expo = self.coef_expr(self.value(b)) if self.param_only(b) else self.materialize(b)
        return {(self.atom(self.node(base**expo, _CONV, base, expo)),): _ONE}

    def apply(self, op: int, args: list[_Lin]) -> _Lin:
        """The linear combination of ``op(*args)``."""
        if op == ca.OP_ASSIGN:
            return args[0]
        if op == ca.OP_NEG:
            return self.scale(args[0], _Coef.const(-1.0))
        if op == ca.OP_TWICE:
            return self.scale(args[0], _Coef.const(2.0))
        if op in (ca.OP_ADD, ca.OP_SUB):
            return self.add(args[0], args[1], 1.0 if op == ca.OP_ADD else -1.0)
        if op == ca.OP_MUL:
            return self.mul(args[0], args[1])
        if op == ca.OP_SQ:
            return self.mul(args[0], args[0])
        if op == ca.OP_DIV:
            return self.div(args[0], args[1])
        if op == ca.OP_INV:
            return self.div({(): _ONE}, args[0])
        if op in (ca.OP_POW, ca.OP_CONSTPOW):
            return self.power(args[0], args[1])
        if op == ca.OP_ATAN2:
            if all(self.param_only(x) for x in args):
                return self.lin(self.value(args[0]).apply(ca.atan2, np.arctan2, self.value(args[1])))
            y, x = self.materialize(args[0]), self.materialize(args[1])
            return {(self.atom(self.node(self.hy.atan2(y, x), 3 * _CONV, y, x)),): _ONE}
        return self.unary(op, args[0])
