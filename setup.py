"""Build configuration that pyproject.toml cannot express: data from outside the package.

The robot descriptions (`robots/`) and the example task scripts (`scenarios/`) stay at the top
of the repository; the built wheel carries them inside the package, as
`locoplan/_data/robots/` and `locoplan/_data/scenarios/` (setuptools' package-dir mapping),
where `locoplan.robot.description.robots_dir` and `locoplan examples` find them once
installed. Everything else (metadata, dependencies, entry points) is in pyproject.toml.
"""

from pathlib import Path

from setuptools import find_namespace_packages, setup

# Folder of this repository -> where it goes in the package.
DATA_TREES = {"robots": "locoplan._data.robots", "scenarios": "locoplan._data.scenarios"}


def data_packages() -> dict[str, str]:
    """Every folder of the data trees as a package name -> its folder (setuptools copies
    package data folder by folder, and warns about sub-folders left out)."""
    packages = {}
    for folder, package in DATA_TREES.items():
        root = Path(folder)
        for path in sorted([root, *root.rglob("*")]):
            parts = path.relative_to(root).parts
            if path.is_dir() and not any(p.startswith(".") or p == "__pycache__" for p in parts):
                packages[".".join([package, *parts])] = path.as_posix()
    return packages


DATA = data_packages()

setup(
    # Namespace discovery, as pyproject's `packages.find` does: a folder of modules without
    # an __init__.py is still shipped.
    packages=[
        *find_namespace_packages(include=["locoplan", "locoplan.*"], exclude=["*__pycache__"]),
        *DATA,
    ],
    package_dir=DATA,
    package_data={name: ["*"] for name in DATA},
    exclude_package_data={name: ["*.pyc"] for name in DATA},
)
