"""Identification end to end: structures compared, the chosen one fitted, refined and given intervals.

1. Every record is prepared (:func:`pendulab.identify.preprocess.prepare`; records sampled
   differently on one common grid, :func:`~pendulab.identify.preprocess.common_interval`) and
   reduced to its normal equations.
2. **Structure from the data.** The nested structures :data:`STRUCTURES` (ideal rigid links;
   + viscous friction; + Coulomb friction; + rotor inertia; + torque-reading offsets) are fitted by
   the consistent regression and compared by the leave-one-record-out torque residual and by
   BIC. The chosen structure is the smallest whose cross-validated error is within
   :data:`CV_TOLERANCE` of the best: a parameter is added only when held-out records say it pays.
3. The chosen structure's base parameters are refined on the measured angles (output error,
   :func:`pendulab.identify.output_error.fit_output_error`) and realized as consistent physical
   parameters nearest the prior (:func:`pendulab.identify.fit.realize`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from .._inputs import checked
from ..model.plant_file import IdentifiedPlant
from .fit import INERTIAL, Normals, fit_regression, normals, realize, regressor_rows
from .output_error import OutputErrorFit, fit_output_error
from .preprocess import DEFAULT_CUTOFF_HZ, Prepared, common_interval, prepare
from .records import Record
from .regressor import STANDARD_NAMES, BaseParameters, base_parameters, standard_to_robot

__all__ = ["STRUCTURES", "CV_TOLERANCE", "StructureScore", "Identification", "compare_structures", "choose_structure", "identify"]

#: Nested model structures: name and the standard parameters it fits.
STRUCTURES: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("rigid", INERTIAL),
    ("+viscous", (*INERTIAL, "b1", "b2")),
    ("+coulomb", (*INERTIAL, "b1", "b2", "cf1", "cf2")),
    ("+rotor", (*INERTIAL, "b1", "b2", "cf1", "cf2", "Ir")),
    ("+offset", (*INERTIAL, "b1", "b2", "cf1", "cf2", "Ir", "o1", "o2")),
)

#: A richer structure is chosen only if it lowers the cross-validated error by more than this fraction.
CV_TOLERANCE = 0.01

#: Preferred order of keeping regressor columns as base parameters: the unidentifiable masses last.
_BASE_ORDER: tuple[str, ...] = ("h1", "I1", "h2", "I2", "Ir", "b1", "b2", "cf1", "cf2", "o1", "o2", "m2", "m1")


@dataclass(frozen=True)
class StructureScore:
    """How one structure does.

    Attributes
    ----------
    name : str
        The structure.
    n_base : int
        Identifiable parameters it fits.
    cv_rms : numpy.ndarray, shape (2,)
        Leave-one-record-out torque residual RMS per joint [N.m].
    cv_score : float
        Weighted mean square of the held-out residual (the joints weighted as in the fit) [-].
    bic : float
        Bayesian information criterion on all records, with the effective sample count of a
        band-limited signal (``2 cutoff`` samples per second) [-].
    """

    name: str
    n_base: int
    cv_rms: np.ndarray
    cv_score: float
    bic: float


@dataclass(frozen=True)
class Identification:
    """The result of :func:`identify`.

    Attributes
    ----------
    plant : IdentifiedPlant
        Parameters with standard errors, offsets and provenance.
    structures : tuple of StructureScore
        The comparison.
    chosen : str
        The chosen structure's name.
    base : BaseParameters
        Its identifiable combinations.
    regression_pi : dict of str to float
        The regression's standard parameters.
    output_error : OutputErrorFit
        The refinement (base parameter values and covariance).
    pi : dict of str to float
        Final standard parameters (physically realized).
    prepared : tuple of Prepared
        The prepared records.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.identify import Record, identify
    >>> from pendulab.identify.datasets import C1_EXCITATION, c1_record
    >>> from pendulab.identify.published import C1_GEOMETRY, DFKI_C1
    >>> from pendulab.identify.regressor import robot_to_standard
    >>> records = [c1_record(stamp) for stamp in C1_EXCITATION[:2]]  # two of the robot's measured records
    >>> short = [Record(r.name, r.t[:1000], r.q[:1000], r.tau[:1000]) for r in records]  # their first 2 s
    >>> prior = robot_to_standard(DFKI_C1["1.0"])  # DFKI's model of the robot: start values of the masses
    >>> result = identify(short, C1_GEOMETRY, prior)  # link lengths, g and gear ratio known
    >>> for s in result.structures:  # leave-one-record-out torque error and BIC of every structure
    ...     print(f"{s.name:9} {s.n_base:2d} base parameters  held-out {s.cv_score:.2f}  BIC {s.bic:.0f}")
    rigid      4 base parameters  held-out 4.71  BIC 88
    +viscous   6 base parameters  held-out 5.19  BIC 55
    +coulomb   8 base parameters  held-out 2.20  BIC 32
    +rotor     9 base parameters  held-out 3.05  BIC 36
    +offset   11 base parameters  held-out 3.10  BIC 43
    >>> result.chosen, result.base.names[:3]  # the motion determines combinations, not every mass
    ('+coulomb', ('h1 + 0.2 m2', 'I1 + 0.04 m2', 'h2'))
    >>> bool(result.pi["I2"] * result.pi["m2"] >= result.pi["h2"] ** 2)  # a physically consistent link 2
    True
    """

    plant: IdentifiedPlant
    structures: tuple[StructureScore, ...]
    chosen: str
    base: BaseParameters
    regression_pi: dict[str, float]
    output_error: OutputErrorFit
    pi: dict[str, float]
    prepared: tuple[Prepared, ...]

    def vector(self) -> np.ndarray:
        """Final standard parameters in :data:`STANDARD_NAMES` order.

        Returns
        -------
        numpy.ndarray, shape (13,)
            The values.
        """
        return np.array([self.pi[n] for n in STANDARD_NAMES])


def structure_base(preps: Sequence[Prepared], structure: Sequence[str], fixed: Mapping[str, float]) -> BaseParameters:
    """The base parameters of a structure on these records' regressor.

    Parameters
    ----------
    preps : sequence of Prepared
        Records.
    structure : sequence of str
        Standard parameters fitted.
    fixed : mapping of str to float
        Known geometry.

    Returns
    -------
    BaseParameters
        The identifiable combinations.
    """
    order = [n for n in _BASE_ORDER if n in structure]
    cols = [STANDARD_NAMES.index(n) for n in order]
    Y = np.concatenate([regressor_rows(p, fixed)[::5] for p in preps]).reshape(-1, len(STANDARD_NAMES))
    return base_parameters(Y[:, cols], order)


def compare_structures(
    data: Sequence[Normals], preps: Sequence[Prepared], fixed: Mapping[str, float], prior: Mapping[str, float], cutoff_hz: float
) -> tuple[StructureScore, ...]:
    """Leave-one-record-out error and BIC of every structure of :data:`STRUCTURES`.

    Parameters
    ----------
    data : sequence of Normals
        Per record (at least two).
    preps : sequence of Prepared
        The same records, prepared.
    fixed : mapping of str to float
        Known geometry.
    prior : mapping of str to float
        Prior standard parameters.
    cutoff_hz : float
        The low-pass cutoff used [Hz] (effective sample count of the BIC).

    Returns
    -------
    tuple of StructureScore
        One per structure, in :data:`STRUCTURES` order.

    Raises
    ------
    ValueError
        Fewer than two records.
    """
    if len(data) < 2:
        raise ValueError(f"structure comparison needs at least two records (leave one out), got {len(data)}")
    total = sum(data[1:], start=data[0])
    weights = 1.0 / np.maximum(fit_regression(total, STRUCTURES[-1][1], prior, np.ones(2)).rms, 1e-9) ** 2
    n_eff = sum(p.use.sum() * p.dt for p in preps) * 2.0 * cutoff_hz
    scores = []
    for name, structure in STRUCTURES:
        sq = np.zeros(2)
        for k in range(len(data)):
            fit = fit_regression([d for i, d in enumerate(data) if i != k], structure, prior, weights)
            sq += data[k].rms(fit.vector()) ** 2 * data[k].n
        cv_ms = sq / total.n
        full = fit_regression(total, structure, prior, weights)
        n_base = len(structure_base(preps, structure, fixed).independent)
        wms = float(weights @ full.rms**2) / 2
        bic = float(n_eff * np.log(wms) + n_base * np.log(n_eff))
        scores.append(StructureScore(name, n_base, np.sqrt(cv_ms), float(weights @ cv_ms) / 2, bic))
    return tuple(scores)


def choose_structure(scores: Sequence[StructureScore]) -> StructureScore:
    """The smallest structure within :data:`CV_TOLERANCE` of the best cross-validated score.

    Parameters
    ----------
    scores : sequence of StructureScore
        From :func:`compare_structures`, smallest first.

    Returns
    -------
    StructureScore
        The chosen one.
    """
    best = min(s.cv_score for s in scores)
    return next(s for s in scores if s.cv_score <= best * (1.0 + CV_TOLERANCE))


@checked(cutoff_hz="cutoff")
def identify(
    records: Sequence[Record],
    fixed: Mapping[str, float],
    prior: Mapping[str, float],
    *,
    cutoff_hz: float = DEFAULT_CUTOFF_HZ,
    torque_limit: tuple[float, float] = (np.inf, np.inf),
    structure: str = "auto",
    progress: Callable[[int, float], None] | None = None,
    meta: Mapping[str, object] | None = None,
) -> Identification:
    """Identify the robot from measured records (see the module docstring).

    Parameters
    ----------
    records : sequence of Record
        Measured records (at least two, for the structure comparison).
    fixed : mapping of str to float
        Known geometry: link lengths ``l1, l2`` [m], gravity ``g`` [m/s^2], gear ratio ``gr``.
    prior : mapping of str to float
        Prior standard parameters (masses; start values).
    cutoff_hz : float, default :data:`~pendulab.identify.preprocess.DEFAULT_CUTOFF_HZ`
        Low-pass cutoff [Hz].
    torque_limit : tuple of float, default (inf, inf)
        Saturation of the input torque per joint [N.m].
    structure : str, default "auto"
        ``"auto"`` (chosen from the data) or a name of :data:`STRUCTURES`.
    progress : callable, optional
        Called with (iteration, RMS angle error [rad]) during the output-error stage.
    meta : mapping, optional
        Provenance stored in the plant file.

    Returns
    -------
    Identification
        The identified plant and the evidence.

    Raises
    ------
    ValueError
        An unknown structure name, fewer than two records, or a record that cannot be prepared.

    Examples
    --------
    RealAIGym's C.1 robot from two of its shipped excitation records (cut to 2 s to keep this
    example quick; ``pendulab identify --dataset c1`` fits all eight, 10 s each):

    >>> import pendulab as pl
    >>> from pendulab.identify import Record, identify
    >>> from pendulab.identify.datasets import C1_EXCITATION, c1_record
    >>> from pendulab.identify.published import C1_GEOMETRY, DFKI_C1
    >>> from pendulab.identify.regressor import robot_to_standard
    >>> records = [c1_record(stamp) for stamp in C1_EXCITATION[:2]]  # two of the robot's measured records
    >>> short = [Record(r.name, r.t[:1000], r.q[:1000], r.tau[:1000]) for r in records]  # their first 2 s
    >>> prior = robot_to_standard(DFKI_C1["1.0"])  # DFKI's model of the robot: start values of the masses
    >>> result = identify(short, C1_GEOMETRY, prior)  # link lengths, g and gear ratio known
    >>> result.chosen  # the structure the held-out records ask for
    '+coulomb'
    >>> print(f"Coulomb friction {result.plant.params['cf1']:.2f} and {result.plant.params['cf2']:.2f} N.m")
    Coulomb friction 0.14 and 0.11 N.m
    >>> bool(max(result.plant.meta["fit_angle_rms"]) < 0.01)  # the fitted model follows the measured angles [rad]
    True
    >>> model = pl.rigid(**result.plant.rigid_kwargs())  # the identified robot as a pendulab model
    """
    names = [n for n, _ in STRUCTURES]
    if structure != "auto" and structure not in names:
        raise ValueError(f"structure must be 'auto' or one of {names}, got {structure!r}")
    if len(records) < 2:
        raise ValueError(f"identification needs at least two records (one is held out to compare structures), got {len(records)}")
    grid = common_interval(records)  # records sampled differently share the coarsest grid (the output-error fit needs one)
    preps = tuple(prepare(r, cutoff_hz, torque_limit, grid) for r in records)
    data = [normals(p, fixed) for p in preps]
    scores = compare_structures(data, preps, fixed, prior, cutoff_hz)
    chosen = choose_structure(scores) if structure == "auto" else scores[names.index(structure)]
    free = dict(STRUCTURES)[chosen.name]
    reg = fit_regression(data, free, prior)
    base = structure_base(preps, free, fixed)
    oe = fit_output_error(preps, base, reg.pi, fixed, progress=progress)
    pi = realize(base, oe.beta, prior, free)
    se_base = dict(zip(base.independent, oe.stderr().tolist(), strict=True))
    robot = standard_to_robot(pi, fixed)
    stderr = {n: se_base.get(n, float("nan")) for n in ("I1", "I2", "Ir", "b1", "b2", "cf1", "cf2") if n in free}
    stderr.update(m1=float("nan"), m2=float("nan"))
    stderr["r1"] = se_base["h1"] / pi["m1"]
    stderr["r2"] = se_base["h2"] / pi["m2"]
    info = {
        "structure": chosen.name,
        "records": [p.name for p in preps],
        "cutoff_hz": cutoff_hz,
        "base_parameters": {n: [float(b), float(s)] for n, b, s in zip(base.names, oe.beta, oe.stderr(), strict=True)},
        "offset_stderr": [se_base.get("o1", 0.0), se_base.get("o2", 0.0)],
        "structures": [
            {"name": s.name, "n_base": s.n_base, "cv_rms": s.cv_rms.tolist(), "cv_score": s.cv_score, "bic": s.bic}
            for s in scores
        ],
        "fit_angle_rms": oe.angle_rms.tolist(),
        "quantum": {"angle": preps[0].quantum[0].tolist(), "torque": preps[0].quantum[1].tolist()},
        **(meta or {}),
    }
    plant = IdentifiedPlant(params=robot, stderr=stderr, torque_offset=(pi["o1"], pi["o2"]), structure=free, meta=info)
    return Identification(
        plant=plant,
        structures=scores,
        chosen=chosen.name,
        base=base,
        regression_pi=reg.pi,
        output_error=oe,
        pi=pi,
        prepared=preps,
    )
