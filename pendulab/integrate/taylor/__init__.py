"""heyoka adaptive Taylor family: ``method="taylor"``, its ODE built from the CasADi graph.

The equations of motion are never typed here. :func:`translate` walks the
model's CasADi SX Function ``rhs(x, u, p)`` instruction by instruction
(``n_instructions``, ``instruction_id/input/output/constant``, ``casadi.OP_*``)
and rebuilds it as heyoka expressions, simplifying on the way so that the
compiled Taylor recursions are as short as those of hand-written equations
(heyoka's decomposition: rigid model 40 elementary operations, as many as the
textbook equations typed by hand; elastic model 51, as many as Newton's law
projected on the springs, with as many products, divisions and sine/cosine
pairs; see ``benchmarks/results/fastpath.md``):

* **Parameter coefficients are hoisted.** Every value is kept as a linear
  combination of monomials (sorted products of state-dependent factors) with
  coefficients that depend on ``p`` only, so ``0.5*m*(2*(L*s))`` is one
  coefficient times ``s``. Each distinct coefficient (``m2*g``,
  ``m1*lc1**2 + m2*L1**2 + I1``, ...) becomes one runtime parameter of the
  heyoka system, computed in NumPy from ``p`` once per run
  (:attr:`TaylorSystem.derived`); no value is compiled in, so
  ``model.with_params(...)`` never recompiles.
* **Folding.** Numeric constants fold; products by 0 or 1 and sums with 0
  vanish; like terms merge; identical coefficients share one parameter and
  coefficients in a small rational ratio factor out of a sum. An opposite
  coefficient is a parameter of its own: heyoka takes ``-par`` for a series,
  so ``(-par) * x`` would be a product of two series, not a scaling.
  Coefficient identities are tested at three random parameter points (a
  non-zero algebraic function of the parameters does not vanish to 1e-11 at
  three random points), so identically-cancelling terms disappear.
* **Trigonometric identities** between pairs of terms:
  ``sin(a)**2 + cos(a)**2 = 1`` (the mass matrix is built from it) and
  ``cos(a)cos(b) + sin(a)sin(b) = cos(a - b)`` and its three siblings. A
  sine or cosine is keyed by its angle as a linear combination with a
  canonical sign, so the angles these identities build (``(a - b) - a + a``)
  are the atom of ``a - b``, ``cos(0) = 1``, ``sin(0) = 0`` and
  ``sin(b - a) = -sin(a - b)``: one sine/cosine pair per distinct angle.
* **Reciprocals cancel.** ``a / b`` is ``a`` times the reciprocal of each
  factor of ``b``; monomials may hold a factor and its reciprocal, which
  cancel when they multiply (``r * (x / r) = x``: the elastic model's 2 x 2
  block inverses multiply and divide by the spring lengths). A monomial is
  emitted as one quotient and a sum sharing a reciprocal is divided once, so
  each equation of the elastic model divides once.
* **Offsets.** ``a + b x`` whose coefficients satisfy ``a / b = r p``
  identically (``p`` a model parameter, ``r`` a small rational) becomes
  ``b (x + r p)``: the spring force ``k (r - L)`` keeps its stretch, exact
  near rest length and one atom shared by every equation, instead of the
  difference ``k r - k L`` of two large hoisted numbers.
* **Expansion and re-factoring.** Monomial-times-sum products are expanded so
  that cancellations and identities show up; sums are rebuilt with the common
  factors pulled out greedily (Horner; on a tie a state-dependent factor
  before an input). Expanding may also duplicate shared sums, so the graph is
  walked with a few strategies and the one with the lowest estimated Taylor
  cost (convolutions + a tenth of the linear operations) is kept.
* **Specialisation on structural zeros.** Parameters whose value is exactly 0
  for this model (dampers ``b1, b2, c1, c2``, inertias ``I1, I2``; any zero
  parameter) and inputs that are identically zero over the run enter as the
  constant 0, so their terms disappear. ``lc1 = L1`` is not specialised:
  parameters only appear inside hoisted coefficients, whose values are
  computed numerically, so equal values cannot shorten the ODE.

Runtime parameters of the compiled system, in order: ``par[0], par[1]`` are
the torques ``tau1, tau2`` (they stay in the ODE, so a new torque on each
output interval costs one assignment; unused when specialised to zero), then
the hoisted coefficients ``par[2:]`` (:attr:`TaylorSystem.coefficients`).
Reassociation changes results at the rounding level only.

**Compilation cache.** A compiled ``taylor_adaptive`` depends on the
*structure key* ``(kind, zero parameters, zero inputs, tol, compact_mode,
high_accuracy)`` (:class:`StructureKey`); it is compiled once per key and
process (:func:`compile_count` counts compilations) and reused by every run
with that key: time, state and parameters are reset, nothing is recompiled.
Changing a non-zero parameter value keeps the key; a parameter moving between
zero and non-zero gives a new structure. heyoka's Taylor order follows from
``tol``, so ``tol`` is part of the key. Across processes, heyoka (>= 7.10)
keeps its own on-disk JIT cache (``heyoka.llvm_state.get_diskcache_path()``,
on by default): a new process re-translates the graph (10-200 ms) and skips
LLVM's optimisation and code generation on a hit. pendulab adds no cache file
of its own (heyoka's serialised integrators would need a version and CPU
check that its disk cache already does).

**Outputs.** ``simulate`` evaluates the outputs on the grid of a Taylor run with the
model's ``outputs`` graph compiled as a heyoka ``cfunc`` (:mod:`.outputs`, once per model kind
and process, from the second run of that kind on): ~6x cheaper than element-wise NumPy.

**Tolerance mapping.** heyoka has one tolerance ``tol``, applied as a
relative error where the state's norm is above 1 and as an absolute one
below: ``tol = min(rtol, atol)``. The order follows from it (15 at 1e-12,
19 at 1e-15). ``max_step`` maps to heyoka's ``max_delta_t``.

**Inputs.** A constant input runs one ``propagate_grid`` over the whole output
grid (dense output: steps do not stop at output times); a sampled input runs
one ``propagate_grid`` per run of equal consecutive rows (each ends exactly on
the time where the input jumps); a feedback runs one ``propagate_until`` per
output interval, the torque set in between.

Options (``simulate(..., options={...})``): ``compact_mode`` (bool, default
False: heyoka's compact mode compiles faster, 2-5x on the elastic model, and runs 2-3x slower),
``high_accuracy`` (bool, default False), ``max_steps`` (int >= 0, default 0 =
unlimited; reaching it raises
:class:`~pendulab.integrate.registry.SimulationError`).

heyoka is optional (``pip install "pendulab[taylor]"``; wheels for Linux
x86-64 and aarch64 only). It is imported when a Taylor run starts, so this
module imports without it; the run then raises :class:`TaylorUnavailableError`
(an ``ImportError``) naming the extra.
"""

from .availability import EXTRA_HINT, TaylorUnavailableError
from .cache import StructureKey, clear_cache, compile_count, compiled_integrator, structure_key
from .runner import METHOD_SPECS, run_taylor
from .translate import TaylorSystem, translate

__all__ = [
    "METHOD_SPECS",
    "TaylorSystem",
    "TaylorUnavailableError",
    "StructureKey",
    "translate",
    "structure_key",
    "compiled_integrator",
    "EXTRA_HINT",
    "compile_count",
    "clear_cache",
    "run_taylor",
]
