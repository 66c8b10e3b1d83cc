"""Helpers for the io tests: raw UFF58 datasets written with pyuff directly (independent of jointdb's writer)."""

from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[1] / "data"
REAL_UFF = DATA / "measured-accelerance-3refs.uff"


def raw58(rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1, x=None, data=None, *, func_type=4, num=12, den=13,
          abscissa=18, even=True, binary=False, labels=("NONE", "NONE", "NONE")):
    """A dataset-58 dict for pyuff.UFF.write_sets."""
    x = np.arange(10.0) if x is None else np.asarray(x, dtype=float)
    if data is None:
        rng = np.random.default_rng(rsp_node * 100 + ref_node * 10 + abs(rsp_dir))
        data = rng.normal(size=x.size) + 1j * rng.normal(size=x.size)
    return {
        "type": 58, "binary": int(binary), "id1": "raw", "func_type": func_type,
        "rsp_node": rsp_node, "rsp_dir": rsp_dir, "ref_node": ref_node, "ref_dir": ref_dir,
        "ord_data_type": 6 if np.iscomplexobj(data) else 4, "abscissa_spacing": int(even),
        "abscissa_spec_data_type": abscissa, "ordinate_spec_data_type": num, "orddenom_spec_data_type": den,
        "abscissa_axis_units_lab": labels[0], "ordinate_axis_units_lab": labels[1],
        "orddenom_axis_units_lab": labels[2], "data": np.asarray(data), "x": x,
    }


def write_raw(path, datasets):
    import pyuff

    path = Path(path)
    if path.exists():
        path.unlink()
    uff = pyuff.UFF(str(path))
    uff.write_sets(list(datasets), mode="add")  # pyuff: binary + "overwrite" truncates the header
    return path
