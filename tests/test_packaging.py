"""The design card's folders install into one `rei` namespace, and nothing generic leaks."""

from __future__ import annotations

import importlib
import importlib.util
import runpy

from tests.conftest import REPO


def test_every_stage_folder_maps_into_rei() -> None:
    setup = runpy.run_path(str(REPO / "setup.py"), run_name="not_main")
    packages: list[str] = setup["PACKAGES"]
    assert all(p == "rei" or p.startswith("rei.") for p in packages)
    for stage in ("rei.lang", "rei.grammars", "rei.generators", "rei.runtime", "rei.catalogue"):
        assert stage in packages
        importlib.import_module(stage)
    # Every folder with an __init__.py is a listed package (nothing silently left out).
    for folder, name in setup["FOLDERS"].items():
        for init in (REPO / name).rglob("__init__.py"):
            rel = init.parent.relative_to(REPO / name).parts
            if "__pycache__" not in rel:
                assert ".".join((folder, *rel)) in packages


def test_no_generic_top_level_names_are_importable() -> None:
    for generic in ("runtime", "generators", "catalogue", "grammars"):
        spec = importlib.util.find_spec(generic)
        assert spec is None or "site-packages" not in (spec.origin or ""), generic


def test_grammars_and_default_catalogue_ship_as_package_data() -> None:
    from importlib import resources

    assert resources.files("rei.grammars").joinpath("room.tx").is_file()
    assert resources.files("rei.grammars").joinpath("mission.tx").is_file()
    assert resources.files("rei.catalogue").joinpath("default.toml").is_file()
