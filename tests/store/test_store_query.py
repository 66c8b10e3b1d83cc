"""Nearest-joint query on a catalogue where the right answer is known; interpolation."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from store_helpers import spring_joint

from jointdb.errors import InputError, NotFoundError
from jointdb.store import BlobStore, Conditions, OutsideCatalogueWarning

TORQUES = {"TH-10": 10.0, "TH-20": 20.0, "TH-40": 40.0, "TH-80": 80.0}


def _k(torque):
    return 1e6 * torque  # stiffness grows with torque in this synthetic catalogue


@pytest.fixture
def catalogue(repo):
    for name, torque in TORQUES.items():
        repo.catalogue(name, "tool-holder", spring_joint(k=(_k(torque), 8e4)),
                       Conditions(("tungsten-carbide", "steel"), torque_nm=torque,
                                  geometry={"diameter_m": 0.02}), "spring-damper-planar")
    repo.catalogue("TH-steel-20", "tool-holder", spring_joint(k=(3e7, 8e4)),
                   Conditions(("steel", "steel"), torque_nm=20.0, geometry={"diameter_m": 0.032}),
                   "spring-damper-planar")
    # another type with the exact requested conditions must never be returned
    repo.catalogue("HS-20", "holder-spindle", spring_joint(k=(5e8, 8e6)),
                   Conditions(("tungsten-carbide", "steel"), torque_nm=22.0), "spring-damper-planar")
    return repo


def test_nearest_by_torque_with_explained_distance(catalogue):
    with warnings.catch_warnings():
        # inside the range: no extrapolation warning (only that class is made an error, so an
        # unrelated ResourceWarning from garbage collection cannot be raised here)
        warnings.simplefilter("error", OutsideCatalogueWarning)
        m = catalogue.nearest("tool-holder", Conditions(("carbide", "steel"), torque_nm=22.0,
                                                         geometry={"diameter_m": 0.02}), k=3)
    assert [x.version.name for x in m] == ["TH-20", "TH-40", "TH-10"]
    spread = math.log(80.0 / 10.0)  # ln range of catalogued torques of this type
    assert m[0].per_condition["torque_nm"] == pytest.approx(math.log(22 / 20) / spread, rel=1e-9)
    assert m[1].per_condition["torque_nm"] == pytest.approx(math.log(40 / 22) / spread, rel=1e-9)
    assert m[0].per_condition["materials"] == 0.0
    assert m[0].per_condition["geometry.diameter_m"] == 0.0
    assert m[0].distance == pytest.approx(m[0].per_condition["torque_nm"])
    assert all(x.version.joint_type == "tool-holder" for x in m)
    assert not any(x.extrapolating for x in m)


def test_material_mismatch_and_geometry_terms(catalogue):
    m = catalogue.nearest("tool-holder", Conditions(("steel", "steel"), torque_nm=20.0,
                                                     geometry={"diameter_m": 0.032}), k=2)
    assert m[0].version.name == "TH-steel-20" and m[0].distance == 0.0
    second = m[1]
    assert second.version.name == "TH-20"
    assert second.per_condition["materials"] == pytest.approx(2 / 3)  # {WC,St} vs {St,St}: 1 − 1/3
    assert second.per_condition["geometry.diameter_m"] == pytest.approx((0.032 - 0.02) / 0.032)
    assert second.distance == pytest.approx(math.hypot(2 / 3, 0.012 / 0.032))


def test_outside_range_is_warned_and_flagged(catalogue):
    with pytest.warns(OutsideCatalogueWarning, match="torque_nm"):
        m = catalogue.nearest("tool-holder", Conditions(torque_nm=200.0), k=1)
    assert m[0].version.name == "TH-80" and m[0].extrapolating and m[0].outside_range == ("torque_nm",)


def test_joint_types_are_never_mixed(catalogue):
    m = catalogue.nearest("holder-spindle", Conditions(torque_nm=22.0), k=5)
    assert [x.version.name for x in m] == ["HS-20"]
    with pytest.raises(NotFoundError, match="holder-spindle, tool-holder"):
        catalogue.nearest("bolted-flange", Conditions(torque_nm=22.0))
    with pytest.raises(InputError, match="k must be"):
        catalogue.nearest("tool-holder", Conditions(), k=0)


def test_only_current_versions_rank_and_time_pinning(catalogue):
    before = catalogue.get("TH-20").created_at
    catalogue.catalogue("TH-20", "tool-holder", spring_joint(k=(_k(21), 8e4)),
                        Conditions(("tungsten-carbide", "steel"), torque_nm=60.0, geometry={"diameter_m": 0.02}),
                        "spring-damper-planar", force=True)
    m = catalogue.nearest("tool-holder", Conditions(torque_nm=20.0), k=5)
    names = [(x.version.name, x.version.version) for x in m]
    assert ("TH-20", 1) not in names and ("TH-20", 2) in names  # corrected version supersedes
    old = catalogue.nearest("tool-holder", Conditions(torque_nm=20.0), k=1, at=before)
    assert (old[0].version.name, old[0].version.version) == ("TH-20", 1)
    catalogue.deprecate("TH-20", 2)  # deprecated version: the previous one is current again
    m = catalogue.nearest("tool-holder", Conditions(torque_nm=20.0), k=1)
    assert (m[0].version.name, m[0].version.version) == ("TH-20", 1)
    catalogue.deprecate("TH-20")  # whole joint deprecated: gone from answers
    m = catalogue.nearest("tool-holder", Conditions(torque_nm=20.0), k=10)
    assert "TH-20" not in [x.version.name for x in m]


def test_ranking_never_loads_blobs(catalogue, monkeypatch):
    def boom(self, digest):
        raise AssertionError("nearest() must not read FRF blobs")

    monkeypatch.setattr(BlobStore, "get", boom)
    with pytest.warns(OutsideCatalogueWarning, match="materials"):  # no catalogued joint is steel only
        m = catalogue.nearest("tool-holder", Conditions(torque_nm=30.0, materials=("steel",)), k=4)
    assert len(m) == 4


def test_interpolation_is_in_dynamic_stiffness(catalogue):
    m = catalogue.nearest("tool-holder", Conditions(("carbide", "steel"), torque_nm=math.sqrt(20.0 * 40.0)), k=2)
    assert {x.version.name for x in m} == {"TH-20", "TH-40"}
    assert m[0].distance == pytest.approx(m[1].distance)  # geometric mean: equidistant in log torque
    ij = catalogue.interpolate(m)
    assert ij.label == "interpolated" and "INTERPOLATED" in ij.describe()
    assert {n for n, _, _ in ij.neighbours} == {"TH-20", "TH-40"}
    assert [w for _, _, w in ij.neighbours] == pytest.approx([0.5, 0.5])
    # Z = H^-1 = k + iωc: the neighbours' stiffness and damping combined as a power law (weighted geometric mean)
    weights = {n: wt for n, _, wt in ij.neighbours}
    z = 1.0 / ij.frf.values[:, 0, 0]
    w = ij.frf.omega
    k_mix = _k(20) ** weights["TH-20"] * _k(40) ** weights["TH-40"]
    assert np.allclose(z.real, k_mix, rtol=1e-12)
    assert np.allclose(z.imag / w, 100.0, rtol=1e-9)
    # averaging receptances instead would give a different (wrong) stiffness
    h_avg = 0.5 * (catalogue.load_frf(m[0].version).values + catalogue.load_frf(m[1].version).values)
    assert not np.allclose((1.0 / h_avg[:, 0, 0]).real, k_mix, rtol=1e-3)


def test_interpolation_refuses_mismatched_neighbours(catalogue):
    catalogue.catalogue("TH-3dof", "tool-holder", spring_joint(k=(1e7,), c=(90.0,), dofs=("3x",)),
                        Conditions(torque_nm=20.0), "n-point-translational")
    m = catalogue.nearest("tool-holder", Conditions(torque_nm=20.0), k=3)
    with pytest.raises(InputError, match="model kind and DOFs must match"):
        catalogue.interpolate(m)
    with pytest.raises(InputError, match="no neighbours"):
        catalogue.interpolate([])


def test_cached_candidates_see_writes_from_other_processes(catalogue, backend):
    first = catalogue.nearest("tool-holder", Conditions(torque_nm=33.0), k=1)
    assert first[0].version.name == "TH-40"
    other = backend.repo()  # another connection pool, as another process would have
    other.catalogue("TH-33", "tool-holder", spring_joint(k=(_k(33), 8e4)), Conditions(torque_nm=33.0),
                    "spring-damper-planar")
    again = catalogue.nearest("tool-holder", Conditions(torque_nm=33.0), k=1)
    assert again[0].version.name == "TH-33" and again[0].distance == 0.0
    other.deprecate("TH-33")
    assert catalogue.nearest("tool-holder", Conditions(torque_nm=33.0), k=1)[0].version.name == "TH-40"
    other.close()
