"""The variables of one model's FMU: value references, start values, tunable parameters, event indicators.

:class:`ModelLayout` (from :func:`layout`) is what the C header (:mod:`pendulab.fmu.codegen`) and
``modelDescription.xml`` (:mod:`pendulab.fmu.model_description`) are written from.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.model import Model
from ..native.codegen import dependency_pattern, identifier_for_kind

__all__ = [
    "SOLVER_NAMES",
    "DEFAULT_TOLERANCE",
    "SPRING_LIMIT",
    "TUNABLE_PARAMS",
    "ModelLayout",
    "event_indicator_names",
    "identifier_for",
    "layout",
]

#: Values of the ``solver`` parameter.
SOLVER_NAMES: tuple[str, ...] = ("dopri5", "rodas4")

# Value-reference bases: one block per variable group keeps references stable
# across models and readable in logs (the elastic model has 8 states, < 100).
VR_TIME, VR_X, VR_DX, VR_U, VR_Y, VR_P = 0, 100, 200, 300, 400, 500
VR_TOL, VR_HMAX, VR_SOLVER = 900, 901, 902
DEFAULT_TOLERANCE = 1e-8
#: Event indicators (value references VR_Z + i): spring margins of the elastic model, r_i - SPRING_LIMIT * L_i.
#: The model is singular at r = 0; when a margin reaches 0 the FMU stops (ME: terminateSimulation at the
#: event, CS: the step ends at the last sub-step before the limit with Discard / terminateSimulation).
VR_Z = 1000
#: 10 % of the rest length: far outside a Hooke spring's range already, and a margin for importers whose
#: integrator tries states past the event before locating it (fmusim's CVode at tolerance 1e-6 overshot the
#: crossing by 0.018 m at 10 m/s; a state with r <= 0 is refused, the model being singular there).
SPRING_LIMIT = 0.1


def event_indicator_names(kind: str, flip_events: bool = False) -> tuple[str, ...]:
    """Names of the FMU's event-indicator variables.

    ``spring_margin1``, ``spring_margin2`` (elastic model: r_i - SPRING_LIMIT L_i), then, with
    ``flip_events``, ``flip_margin1``, ``flip_margin2`` (pi - |theta_i|: 0 when link i passes upright).

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.
    flip_events : bool
        Whether the FMU has flip events (an export option).

    Returns
    -------
    tuple of str
        Spring margins first, then flip margins; empty for the rigid model without flip events.
    """
    springs = ("spring_margin1", "spring_margin2") if kind == "elastic" else ()
    return springs + (("flip_margin1", "flip_margin2") if flip_events else ())


@dataclass(frozen=True)
class ModelLayout:
    """Names, value references and dependency structure of one model's FMU variables.

    Attributes
    ----------
    identifier : str
        Model identifier (C symbol prefix, binary name), e.g. ``pendulab_rigid``.
    kind : {"rigid", "elastic"}
        Model kind.
    nx, nu, ny, np : int
        Numbers of states, inputs, outputs and parameters.
    x_start : ndarray, shape (nx,)
        State start values [SI].
    p_default : ndarray, shape (np,)
        Parameter start values [SI].
    p_tunable : tuple of bool, length np
        Whether each parameter may change during a run.
    p_positive : tuple of bool, length np
        Whether each parameter must be positive.
    dependencies : ndarray of bool, shape (nx + ny, nx + nu + np)
        Structural non-zeros: rows derivatives then outputs; columns states, inputs, then parameters.
    flip_events : bool
        Declare the event indicators pi - abs(theta_i) (Model Exchange: the importer locates every flip).
    """

    identifier: str
    kind: str
    nx: int
    nu: int
    ny: int
    np: int
    x_start: np.ndarray
    p_default: np.ndarray
    p_tunable: tuple[bool, ...]
    p_positive: tuple[bool, ...]
    #: rows: derivatives then outputs; columns: states, inputs, then parameters (structural non-zeros)
    dependencies: np.ndarray
    #: event indicators pi - |theta_i| (Model Exchange: the importer locates every flip of a link)
    flip_events: bool = False

    def vr(self, group: str, index: int = 0) -> int:
        """Value reference of a variable.

        Parameters
        ----------
        group : {"x", "dx", "u", "y", "p"}
            States, derivatives, inputs, outputs or parameters.
        index : int
            Position in the group.

        Returns
        -------
        int
            The value reference.
        """
        base = {"x": VR_X, "dx": VR_DX, "u": VR_U, "y": VR_Y, "p": VR_P}[group]
        return base + index


#: Parameters that may change during a run (FMI "tunable"): environment and
#: dissipation/compliance values, whose change leaves the meaning of the state
#: intact. Masses, lengths and inertias are "fixed": changing them mid-run would
#: make the current state describe a different body; reinstantiate instead.
TUNABLE_PARAMS = frozenset({"g", "b1", "b2", "k1", "k2", "c1", "c2"})


def identifier_for(model: Model) -> str:
    """Model identifier (C symbol prefix, binary name): ``pendulab_rigid`` or ``pendulab_elastic``.

    Parameters
    ----------
    model : Model
        The pendulum.

    Returns
    -------
    str
        ``pendulab_<kind>``.
    """
    return identifier_for_kind(model.kind)


def layout(model: Model, x0: np.ndarray | None = None, flip_events: bool = False) -> ModelLayout:
    """Variable layout of the FMU of ``model``.

    Parameters
    ----------
    model : Model
        The pendulum; its parameters become the parameter start values.
    x0 : ndarray, shape (nx,), optional
        State start values [SI]; default hanging at rest.
    flip_events : bool
        Add the flip event indicators pi - |theta_i|.

    Returns
    -------
    ModelLayout

    Raises
    ------
    ValueError
        ``x0`` has the wrong shape or is not finite.
    """
    x_start = model.rest_state() if x0 is None else model.check_state(x0, "x0")
    if x_start.ndim != 1:
        raise ValueError(f"x0 must have shape ({model.nx},), got shape {x_start.shape}")
    identifier = identifier_for(model)
    deps = dependency_pattern(model.kind)
    names = model.param_names
    return ModelLayout(
        identifier=identifier,
        kind=model.kind,
        nx=model.nx,
        nu=model.nu,
        ny=model.ny,
        np=len(names),
        x_start=np.array(x_start, dtype=float),
        p_default=np.asarray(model.p, dtype=float),
        p_tunable=tuple(n in TUNABLE_PARAMS for n in names),
        p_positive=tuple(info.positive for info in model.param_info),
        dependencies=deps,
        flip_events=bool(flip_events),
    )
