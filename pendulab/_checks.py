"""Argument checks shared across the package (one wording for each kind of error)."""

from __future__ import annotations

import math
from typing import Any

__all__ = ["positive_float", "check_model", "is_interrupt"]


def positive_float(name: str, value: Any, unit: str = "") -> float:
    """``value`` as a positive finite float, else ``ValueError`` naming ``name``, the value and the expectation.

    Parameters
    ----------
    name : str
        Argument name used in the message.
    value : Any
        Received value.
    unit : str
        Optional unit appended to the expectation (e.g. ``"[s]"``).
    """
    suffix = f" {unit}" if unit else ""
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a positive number{suffix}, got {value!r}") from exc
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be a positive finite number{suffix}, got {value!r}")
    return v


def check_model(model: Any, name: str = "model") -> Any:
    """``model`` itself when it is a pendulab ``Model``, else ``TypeError`` naming ``name`` and the type received.

    The one check of every public function that takes a model (analysis,
    linearization, python-control bridge, LQR, simulation), so that a wrong
    argument (a kind name such as ``"rigid"``, ``None``, a parameter object)
    fails with ``TypeError("model must be a pendulab Model, got str")`` instead
    of an ``AttributeError`` deep inside.

    Parameters
    ----------
    model : Any
        Received value.
    name : str
        Argument name used in the message.

    Returns
    -------
    Model
        The same object.

    Raises
    ------
    TypeError
        ``model`` is not a :class:`pendulab.model.model.Model`.
    """
    if not _is_model(model):
        hint = ""
        if isinstance(model, str):
            hint = f"; build one with pendulab.rigid() or pendulab.elastic() (or make_model({model!r}))"
        raise TypeError(f"{name} must be a pendulab Model, got {type(model).__name__}{hint}")
    return model


#: Where the Model class lives; _checks sits in the same layer as model/ and may not import it.
_MODEL_CLASS = ("pendulab.model.model", "Model")


def _is_model(obj: Any) -> bool:
    """True for an instance of ``pendulab.model.model.Model`` (or a subclass), checked without importing it."""
    return any((c.__module__, c.__qualname__) == _MODEL_CLASS for c in type(obj).__mro__)


def is_interrupt(exc: BaseException) -> bool:
    """True when ``exc``, or an exception in its cause/context chain, is a Ctrl-C in disguise.

    CasADi, IPOPT and fmpy turn a ``KeyboardInterrupt`` raised inside their callbacks into their own
    errors; loops that keep going after a failed point must not keep going after an interrupt.

    Parameters
    ----------
    exc : BaseException
        The exception caught.

    Returns
    -------
    bool
        ``KeyboardInterrupt`` in the chain, or a message naming it.
    """
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        seen.add(id(e))
        if isinstance(e, KeyboardInterrupt) or "KeyboardInterrupt" in str(e):
            return True
        e = e.__cause__ or e.__context__
    return False
