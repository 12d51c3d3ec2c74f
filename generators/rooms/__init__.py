"""Systematic generation of test rooms and missions (`rei-gen rooms`).

Rows of a parameter space (full grid, pairwise covering array, or seeded random) are built
into rooms valid by construction, checked with the same rules as `rei-gen check`, described
by difficulty measures (BARN's five plus crowd measures) and written as ordinary .room /
.mission files with an index CSV and a coverage report.

Public API::

    preset_space, ParameterSpace, Factor     the parameter space and its presets
    SuiteRequest, generate, write_suite      build a suite in memory, then write it
    pairwise, uncovered_pairs                the covering array and its check
    Scene, describe, scene_of_documents      difficulty descriptors of any room + mission
    coverage_report                          what a suite covers
"""

from rei.generators.rooms.coverage import coverage_report
from rei.generators.rooms.descriptors import Descriptors, Scene, describe, scene_of_documents
from rei.generators.rooms.design import pairwise, uncovered_pairs
from rei.generators.rooms.space import (
    FACTOR_NAMES,
    PRESETS,
    Factor,
    ParameterError,
    ParameterSpace,
    preset_space,
)
from rei.generators.rooms.suite import (
    INDEX_COLUMNS,
    StageTimes,
    Suite,
    SuiteRequest,
    generate,
    index_csv,
    write_suite,
)
from rei.generators.rooms.writer import read_metadata

__all__ = [
    "FACTOR_NAMES", "INDEX_COLUMNS", "PRESETS", "Descriptors", "Factor", "ParameterError",
    "ParameterSpace", "Scene", "StageTimes", "Suite", "SuiteRequest", "coverage_report",
    "describe", "generate", "index_csv", "pairwise", "preset_space", "read_metadata",
    "scene_of_documents", "uncovered_pairs", "write_suite",
]
