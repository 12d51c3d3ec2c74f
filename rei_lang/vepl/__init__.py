"""The .vepl language: queries over the runtime model, temporal event patterns, signals with
utilities and requirements (thesis 5.1.5-5.2, appendix 9.2.2).

``load_vepl(path)`` gives a checked ``Specification``; ``check_vepl`` gives diagnostics.
This package must never import the runtime or the simulator.
"""

from rei.lang.vepl.document import DEFAULT_VEPL, VeplDocument, analyse_vepl, check_vepl, load_vepl
from rei.lang.vepl.model import Specification

__all__ = ["DEFAULT_VEPL", "Specification", "VeplDocument", "analyse_vepl", "check_vepl",
           "load_vepl"]
