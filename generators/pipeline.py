"""From an input file to generated files: check, concretise, run targets, write all or nothing.

The one path every front end takes (`rei-gen generate`, `textx generate`, tests): the file is
checked with the shared ``Workspace`` (every diagnostic, as a LanguageError), mapped to the
concrete model, and each chosen target renders its files in memory; only when every target
succeeded is the combined tree written, atomically, by ``write_tree``. This module must never
print, exit, or write anything before every target has succeeded.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from rei.generators.concrete import concretise_mission, concretise_room
from rei.generators.errors import GenerationError
from rei.generators.output import OutputTree, write_tree
from rei.generators.targets import GenerationRequest, Target, available_targets, get_target
from rei.lang.errors import Diagnostic, LanguageError
from rei.lang.suggest import did_you_mean
from rei.lang.vepl.document import load_vepl
from rei.lang.vepl_parameters import PARAM_OPTION, ParameterValues
from rei.lang.workspace import Workspace

ALL = "all"


@dataclass(frozen=True)
class GenerationPlan:
    """The files of one generation, in memory, with the target folder each came from."""

    tree: OutputTree
    targets: tuple[str, ...]
    warnings: tuple[Diagnostic, ...]


def build_request(source: Path, options: Mapping[str, str] | None = None,
                  workspace: Workspace | None = None, parameters: ParameterValues = ()
                  ) -> tuple[GenerationRequest, list[Diagnostic]]:
    """The checked, concretised request for ``source`` (with a .vepl's ``parameters`` from
    `--param`); LanguageError with every problem."""
    if parameters and source.suffix not in (".vepl", ".mission"):
        raise GenerationError(f"{PARAM_OPTION}: expected a .vepl file to set parameters of "
                              f"(or a .mission for target 'launch'), found '{source.name}'")
    ws = workspace or Workspace()
    diagnostics = ws.check(source)
    errors = [d for d in diagnostics if d.is_error]
    if errors:
        raise LanguageError(errors)
    warnings = [d for d in diagnostics if not d.is_error]
    opts = dict(options or {})
    if source.suffix == ".room":
        world = concretise_room(ws.room(source))
        return GenerationRequest(source, world, None, opts), warnings
    if source.suffix == ".mission":
        mission = concretise_mission(ws.mission(source))
        return GenerationRequest(source, mission.world, mission, opts, parameters), warnings
    if parameters:
        load_vepl(source, parameters)  # each name declared, every rule kept (LanguageError)
    return GenerationRequest(source, None, None, opts, parameters), warnings


def choose_targets(source: Path, name: str) -> list[Target]:
    """The target called ``name``, or with ``all`` every target accepting the file's suffix."""
    if name == ALL:
        chosen = [t for _, t in sorted(available_targets().items()) if source.suffix in t.accepts]
        if not chosen:
            raise GenerationError(f"expected a target that accepts '{source.suffix}' files, "
                                  f"found none among {', '.join(sorted(available_targets()))}")
        return chosen
    target = get_target(name)
    if source.suffix not in target.accepts:
        raise GenerationError(f"target '{target.name}' expected a file ending in "
                              f"{' or '.join(target.accepts)}, found '{source.name}'")
    return [target]


def plan(source: Path, target: str, options: Mapping[str, str] | None = None,
         workspace: Workspace | None = None, parameters: ParameterValues = ()
         ) -> GenerationPlan:
    """Every file the generation would write, relative to the output folder.

    One target writes into the output folder itself; ``all`` writes each target into a
    sub-folder named after it. ``parameters`` (`--param`, sorted by name) set a .vepl's
    parameter values.
    """
    targets = choose_targets(Path(source), target)
    check_options(targets, options or {})
    if parameters and Path(source).suffix == ".mission":
        refusing = [t.name for t in targets if not getattr(t, "runs_missions", False)]
        if refusing:
            raise GenerationError(f"{PARAM_OPTION}: expected a .vepl file to set parameters "
                                  f"of, or a .mission for target 'launch' (its run.json), "
                                  f"found '{Path(source).name}' for target '{refusing[0]}'")
    request, warnings = build_request(Path(source), options, workspace, parameters)
    tree = render_targets(request, targets, subfolders=target == ALL)
    return GenerationPlan(tree, tuple(t.name for t in targets), tuple(warnings))


def check_options(targets: list[Target], options: Mapping[str, str]) -> None:
    """Refuse option keys no chosen target reads (a typo would otherwise pass silently).

    A target may list the keys it reads in an ``options`` attribute; when one of the chosen
    targets does not, any key might be its, so nothing is refused.
    """
    declared: list[Iterable[str]] = []
    for t in targets:
        keys = getattr(t, "options", None)
        if keys is None:
            return
        declared.append(keys)
    known = sorted({key for keys in declared for key in keys})
    for key in options:
        if key not in known:
            raise GenerationError(
                f"--option {key}: expected a key among {', '.join(known) or 'none'} "
                f"(read by {', '.join(t.name for t in targets)}), found '{key}'"
                + did_you_mean(key, known))


def render_targets(request: GenerationRequest, targets: list[Target], *,
                   subfolders: bool) -> OutputTree:
    """Every target's files in one tree (each in a folder named after it when ``subfolders``)."""
    tree = OutputTree()
    for chosen in targets:
        try:
            files = chosen.generate(request)
        except GenerationError as exc:
            raise GenerationError(f"{request.source}: target '{chosen.name}': {exc}") from None
        tree.merge(files, chosen.name if subfolders else "")
    return tree


def generate(source: Path, target: str, out_dir: Path, options: Mapping[str, str] | None = None,
             workspace: Workspace | None = None, parameters: ParameterValues = ()
             ) -> tuple[GenerationPlan, list[Path]]:
    """Plan, then write every file under ``out_dir`` (all or nothing)."""
    result = plan(source, target, options, workspace, parameters)
    return result, write_tree(result.tree, out_dir)
