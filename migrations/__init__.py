"""Alembic migration environment of the joint database (shipped in the wheel).

Run through ``jointdb db upgrade|downgrade`` or :mod:`jointdb.store._db`;
``alembic.ini`` at the repository root is only a convenience for developers.
"""
