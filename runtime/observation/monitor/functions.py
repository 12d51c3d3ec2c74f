"""User check functions for a .vepl, loaded from a Python module (`--functions MODULE`).

A specification declares ``function clearance(o)``; VIATRA let such external check functions
into patterns, and REI lets ``rei run``, ``rei replay`` and ``rei campaign`` find them in a
module the user names: a dotted module name importable from the current folder or
PYTHONPATH, or the path of a ``.py`` file. Each declared function must be a callable of that
name in the module, called as ``fn(model, *args)``. A module that does not import is bad
input naming the option; a declared function the module lacks is a located error at its
``function`` line, as is a declared function with no module given. This module must never
import the simulator.
"""

from __future__ import annotations

import importlib
import importlib.util
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

from rei.lang.errors import Diagnostic, LanguageError
from rei.lang.suggest import did_you_mean
from rei.lang.vepl.document import load_vepl
from rei.runtime.errors import RunError


def import_functions_module(name: str) -> ModuleType:
    """The user's module: a ``.py`` file, or a dotted name (the current folder searched
    first, as ``python -m`` does)."""
    path = Path(name)
    try:
        if name.endswith(".py") or path.is_file():
            if not path.is_file():
                raise RunError(f"--functions: expected a Python module, found no file "
                               f"'{name}'")
            spec = importlib.util.spec_from_file_location(f"rei_user_functions_{path.stem}",
                                                          path)
            if spec is None or spec.loader is None:
                raise RunError(f"--functions: expected a Python module, found '{name}'")
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
            return module
        here = str(Path.cwd())
        added = here not in sys.path
        if added:
            sys.path.insert(0, here)
        try:
            return importlib.import_module(name)
        finally:
            if added:
                sys.path.remove(here)
    except RunError:
        raise
    except ImportError as exc:
        raise RunError(f"--functions: expected an importable Python module, found '{name}' "
                       f"({exc})") from None
    except Exception as exc:  # noqa: BLE001  (the user's module failed while importing)
        raise RunError(f"--functions: the module '{name}' failed to import: "
                       f"{type(exc).__name__}: {exc}") from None


def load_functions(module_name: str | None, vepl: str | Path | None
                   ) -> Mapping[str, Callable[..., Any]]:
    """The functions the specification (the default one when ``vepl`` is None) declares,
    from ``module_name``; none without a module. Raises RunError (the module) or
    LanguageError (a declared function it lacks, located in the .vepl)."""
    spec = load_vepl(vepl)
    if module_name is None:
        if spec.functions:
            raise LanguageError([Diagnostic(spec.function_spans[name], "VEPL-FUNCTION",
                                            f"function '{name}': expected the module that "
                                            f"defines it (--functions MODULE), found none")
                                 for name in spec.functions])
        return {}
    module = import_functions_module(module_name)
    found: dict[str, Callable[..., Any]] = {}
    problems: list[Diagnostic] = []
    offered = [n for n in vars(module) if not n.startswith("_") and callable(vars(module)[n])]
    for name in spec.functions:
        fn = getattr(module, name, None)
        if callable(fn):
            found[name] = fn
            continue
        span = spec.function_spans[name]
        shown = "a value that is not callable" if fn is not None else "none"
        problems.append(Diagnostic(span, "VEPL-FUNCTION",
                                   f"function '{name}': expected a callable '{name}' in the "
                                   f"module '{module_name}', found {shown}"
                                   + did_you_mean(name, offered)))
    if problems:
        raise LanguageError(problems)
    return found
