"""Event specifications of an ensemble: :class:`Event`, the built-in ``"flip"``, and their resolution.

An event is a scalar function ``g(x, p)`` of the state and the parameters; it *triggers*
when ``g`` crosses zero. A **terminal** event stops the run (its state and time are those
at the crossing); a **recorded** (non-terminal) event only records the time of its first
crossing. Event functions are built from the model's own CasADi symbols and translated to
heyoka with the same translator as the equations of motion.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from .._checks import bounded_int
from ..model.model import Model

__all__ = ["Event", "FLIP", "EventPlan", "resolve_events"]

#: Most events of one ensemble.
MAX_EVENTS = 64
#: Name of the built-in flip event: ``|theta1|`` or ``|theta2|`` reaching pi (terminal).
FLIP = "flip"


@dataclass(frozen=True)
class Event:
    """One event of an ensemble run.

    Attributes
    ----------
    name : str
        Key of the event in :attr:`EnsembleResult.event_times` (unique within an ensemble;
        ``"flip"`` is reserved for the built-in flip event).
    expr : callable or str
        Either a callable ``expr(x, p) -> casadi.SX`` returning a scalar expression of the
        model's state symbols ``x`` (``casadi.SX``, shape (nx, 1), in ``model.state_names``
        order) and parameter symbols ``p`` (shape (np, 1), in ``model.param_names`` order);
        the event function is ``expr(x, p) - value``. Or the name of a state
        (``"theta1"``, ``"omega2"``, ...) or an output (``"x2"``, ``"y2"``, ``"energy"``, ...)
        of the model; the event function is ``signal - value``.
    terminal : bool
        True: the first crossing stops the run; False: the first crossing time is recorded
        and the run goes on.
    direction : {0, 1, -1}
        0: any crossing; 1: only upward crossings (``g`` from negative to positive);
        -1: only downward crossings.
    value : float
        Threshold subtracted from the expression.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.ensemble import Event

    A recorded event by state name: link 1 swinging up through the vertical, after a small release in
    the in-phase mode (shape theta1 : theta2 = 1 : sqrt 2); it first comes a quarter period later.

    >>> up = Event("theta1_up", "theta1", terminal=False, direction=1)
    >>> res = pl.ensemble(pl.rigid(), [[-0.01 / np.sqrt(2), -0.01, 0.0, 0.0]], 2.0, events=[up])  # one run
    >>> w = np.sqrt(9.81 * (2 - np.sqrt(2)))  # in-phase frequency of the 1 kg, 1 m pendulum [rad/s]
    >>> print(f"{res.event_times['theta1_up'][0]:.4f} s, quarter period {np.pi / 2 / w:.4f} s")
    0.6553 s, quarter period 0.6553 s

    A terminal event from an expression of the state symbols: stop when the angles leave a 1 rad circle.

    >>> wide = Event("wide", lambda x, p: x[0] ** 2 + x[1] ** 2, value=1.0)
    >>> kicks = np.array([2.0, 4.0, 6.0])  # omega1 [rad/s] from hanging at rest
    >>> res = pl.ensemble(pl.rigid(), np.column_stack([0 * kicks, 0 * kicks, kicks, 0 * kicks]), 3.0, events=[wide])
    >>> res.status.tolist(), np.round(res.t_final, 3)
    (['ok', 'event', 'event'], array([3.   , 0.326, 0.195]))
    """

    name: str
    expr: Callable[[Any, Any], Any] | str
    terminal: bool = True
    direction: int = 0
    value: float = 0.0


@dataclass(frozen=True)
class EventPlan:
    """Events resolved against a model, in a pickle-friendly form (plain data + serialized CasADi).

    Attributes
    ----------
    names : tuple of str
        Event names, in the order given.
    terminal : tuple of bool
        Per event.
    components : tuple of tuple
        heyoka-level event functions: ``(event index, kind, arg, direction)`` with kind
        ``"square"`` (``x[arg]**2 - pi**2``), ``"state"`` (``x[arg[0]] - arg[1]``) or ``"sx"``
        (row ``arg`` of :attr:`sx_function`'s output).
    sx_function : str
        Serialized CasADi Function ``g(x, u, p)`` of the ``"sx"`` components ("" when none).
    """

    names: tuple[str, ...] = ()
    terminal: tuple[bool, ...] = ()
    components: tuple[tuple[int, str, Any, int], ...] = ()
    sx_function: str = ""

    def signature(self) -> tuple:
        """Hashable key of what the compiled integrator depends on.

        Returns
        -------
        tuple
            ``(terminal, components, sx_function)``.
        """
        return (self.terminal, self.components, self.sx_function)


def resolve_events(model: Model, events: Sequence[Event | str] | None) -> EventPlan:
    """Check event specifications and turn them into an :class:`EventPlan`.

    Parameters
    ----------
    model : Model
        Model whose symbols the event functions use.
    events : sequence of Event or "flip", or None
        The event specifications.

    Returns
    -------
    EventPlan

    Raises
    ------
    ValueError
        An unknown event string, an unknown signal name, a duplicate name, a bad direction,
        or an expression that is not a scalar function of ``x`` and ``p`` (the message names it).
    """
    if events is None:
        return EventPlan()
    if isinstance(events, (str, Event)):
        events = [events]
    try:
        events = list(events)
    except TypeError as exc:
        raise ValueError(f"events must be a sequence of Event or 'flip', got {events!r}") from exc
    bounded_int("number of events", len(events), low=0, high=MAX_EVENTS, why="each event is compiled into the integrator")
    sym = model.symbolic
    names: list[str] = []
    terminal: list[bool] = []
    comps: list[tuple[int, str, Any, int]] = []
    sx_rows: list[Any] = []
    for spec in events:
        k = len(names)
        if isinstance(spec, str):
            if spec != FLIP:
                raise ValueError(f"events: unknown event {spec!r}; expected 'flip' or an Event(name, expr, ...)")
            name, term = FLIP, True
            i1, i2 = model.state_names.index("theta1"), model.state_names.index("theta2")
            comps += [(k, "square", i1, 0), (k, "square", i2, 0)]
        elif isinstance(spec, Event):
            name, term = spec.name, bool(spec.terminal)
            if not isinstance(name, str) or not name:
                raise ValueError(f"events: Event name must be a non-empty str, got {name!r}")
            if spec.direction not in (0, 1, -1):
                raise ValueError(f"events: Event {name!r} direction must be 0, 1 or -1, got {spec.direction!r}")
            try:
                value = float(spec.value)
            except (TypeError, ValueError) as exc:
                raise ValueError(f"events: Event {name!r} value must be a finite number, got {spec.value!r}") from exc
            if not math.isfinite(value):
                raise ValueError(f"events: Event {name!r} value must be a finite number, got {spec.value!r}")
            direction = int(spec.direction)
            if isinstance(spec.expr, str):
                if spec.expr in model.state_names:
                    comps.append((k, "state", (model.state_names.index(spec.expr), value), direction))
                elif spec.expr in model.output_names:
                    y = model.functions["outputs"](sym.x, ca.DM.zeros(model.nu), sym.p)
                    sx_rows.append(y[model.output_names.index(spec.expr)] - value)
                    comps.append((k, "sx", len(sx_rows) - 1, direction))
                else:
                    raise ValueError(
                        f"events: Event {name!r} names unknown signal {spec.expr!r}; expected a state "
                        f"{list(model.state_names)} or an output {list(model.output_names)}"
                    )
            elif callable(spec.expr):
                g = _call_expr(spec, sym, name)
                sx_rows.append(g - value)
                comps.append((k, "sx", len(sx_rows) - 1, direction))
            else:
                raise ValueError(
                    f"events: Event {name!r} expr must be a callable expr(x, p) -> casadi.SX or a signal name, got {spec.expr!r}"
                )
        else:
            raise ValueError(f"events: expected 'flip' or an Event(name, expr, ...), got {spec!r}")
        if name in names:
            raise ValueError(f"events: duplicate event name {name!r}")
        names.append(name)
        terminal.append(term)
    sx_function = ""
    if sx_rows:
        try:
            g = ca.Function("events", [sym.x, sym.u, sym.p], [ca.vertcat(*sx_rows)], ["x", "u", "p"], ["g"])
        except RuntimeError as exc:
            raise ValueError(f"events: an event expression uses symbols other than the model's x and p ({exc})") from exc
        sx_function = g.serialize()
    return EventPlan(tuple(names), tuple(terminal), tuple(comps), sx_function)


def _call_expr(spec: Event, sym: Any, name: str) -> Any:
    try:
        g = spec.expr(sym.x, sym.p)
    except Exception as exc:
        raise ValueError(f"events: Event {name!r} expr(x, p) raised {type(exc).__name__}: {exc}") from exc
    if isinstance(g, (int, float, np.floating, np.integer)):
        g = ca.SX(float(g))
    if not isinstance(g, ca.SX) or g.numel() != 1:
        raise ValueError(f"events: Event {name!r} expr(x, p) must return a scalar casadi.SX, got {g!r}")
    if not ca.depends_on(g, sym.x):
        raise ValueError(f"events: Event {name!r} expr(x, p) does not depend on the state x, got {g!r}")
    return g
