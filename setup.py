"""Maps the design card's top-level folders into the single ``rei`` import namespace.

pyproject.toml holds all metadata; this file only computes the package list, so a new
sub-package inside a stage folder is picked up without editing any list by hand.
"""

from pathlib import Path

from setuptools import setup

HERE = Path(__file__).parent
FOLDERS = {
    "rei.lang": "rei_lang",
    "rei.grammars": "grammars",
    "rei.generators": "generators",
    "rei.runtime": "runtime",
    "rei.catalogue": "catalogue",
}
DATA = ["*.tx", "*.toml", "*.j2", "*.xsd", "*.vepl", "*.css", "*.js", "*.html", "py.typed"]


def _packages() -> tuple[list[str], dict[str, str]]:
    packages: list[str] = []
    package_dir: dict[str, str] = {}
    for name, folder in FOLDERS.items():
        root = HERE / folder
        for init in sorted(root.rglob("__init__.py")):
            rel = init.parent.relative_to(root)
            if "__pycache__" in rel.parts:
                continue
            dotted = ".".join((name, *rel.parts)) if rel.parts else name
            packages.append(dotted)
            package_dir[dotted] = str(Path(folder, *rel.parts))
    return packages, package_dir


PACKAGES, PACKAGE_DIR = _packages()

if __name__ == "__main__":  # setuptools runs this file as __main__; tests import the lists
    setup(
        packages=PACKAGES,
        package_dir=PACKAGE_DIR,
        package_data={pkg: DATA for pkg in PACKAGES},
    )
