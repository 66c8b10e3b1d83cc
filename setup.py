"""Package layout that pyproject.toml cannot express: the Alembic environment lives in the
top-level ``migrations/`` of the repository and ships inside the wheel as ``jointdb.migrations``
(so ``jointdb db upgrade`` works after a plain ``pip install``). Everything else is in
pyproject.toml."""

from setuptools import find_packages, setup

setup(
    packages=find_packages(include=["jointdb", "jointdb.*"]) + ["jointdb.migrations"],
    package_dir={"jointdb.migrations": "migrations"},
)
