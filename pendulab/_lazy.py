"""Public names imported on first use (PEP 562), for the packages whose eager imports cost seconds.

``import pendulab`` used to import SciPy's integrate, CasADi graphs and the ensemble engine (0.6 s idle,
3.4 s loaded), which every CLI start paid, ``--help`` and a one-line option error included, and a Ctrl-C
in that window surfaced as a traceback. A package lists its public names with the module defining each;
:func:`install` gives it the module ``__getattr__`` / ``__dir__`` that import them when first asked for.

Some public names are also submodule names (the function ``pendulab.ensemble`` and the package
``pendulab.ensemble``; ``pendulab.integrate.simulate``). Importing such a submodule makes the import system
bind the submodule over the name; the installed module class ignores exactly that binding, so the name
keeps meaning the public object however the modules were imported. A public function named like a *package*
(``pendulab.ensemble``) carries the package's dotted name as its ``__name__``: ``import pendulab.ensemble.flipmap
as fm`` reaches the function first and then finds the submodule through that name
(``tests/reliability/test_lazy_heavy_imports.py`` imports every module so).
"""

from __future__ import annotations

import importlib
import sys
import types
from collections.abc import Mapping
from typing import Any

__all__ = ["install"]


class _LazyModule(types.ModuleType):
    def __setattr__(self, name: str, value: Any) -> None:
        table = self.__dict__.get("_LAZY_NAMES", {})
        if name in table and isinstance(value, types.ModuleType) and value.__name__ == f"{self.__name__}.{name}":
            return  # the import system binding a submodule over a public name of the same spelling
        super().__setattr__(name, value)


def install(module_name: str, names: Mapping[str, str]) -> None:
    """Serve ``names`` (public name -> defining module, relative to the package) of ``module_name`` lazily.

    Parameters
    ----------
    module_name : str
        The package (its ``__name__``), already in ``sys.modules``.
    names : mapping of str to str
        Public name -> module that defines it (``".integrate"``), imported on first access.
    """
    module = sys.modules[module_name]
    table = dict(names)

    def getattr_(name: str) -> Any:
        source = table.get(name)
        if source is None:
            raise AttributeError(f"module {module_name!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(source, module_name), name)
        module.__dict__[name] = value  # cached: later lookups are plain attribute reads
        return value

    def dir_() -> list[str]:
        return sorted(set(module.__dict__) | set(table))

    module.__dict__.update(_LAZY_NAMES=table, __getattr__=getattr_, __dir__=dir_)
    for name in table:
        if isinstance(module.__dict__.get(name), types.ModuleType):
            del module.__dict__[name]  # a submodule imported before install: the name is the public object
    module.__class__ = _LazyModule
