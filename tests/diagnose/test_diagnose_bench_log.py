"""The benchmark's case log (one JSON line per case) and the time goals it is judged against."""

import gzip
import math

import pytest

from jointdb.diagnose_bench import BenchResult, CaseResult
from jointdb.diagnose_bench._run import effects_from, time_goal


def _case(effect, seconds, cpu, **kw):
    return CaseResult(case=f"{effect}-1000", effect=effect, named=kw.pop("named", effect), names=(effect,),
                      top3=(effect,), improvement=40.0, mismatch_before=1.4, mismatch_after=0.035,
                      seconds=seconds, cpu_seconds=cpu, load=3.5, **kw)


def test_a_logged_case_reads_back_equal_including_non_finite_sigmas():
    r = _case("interface_softening", 60.0, 44.0, level_improvements=(30.0, 41.5, 52.0),
              fitted={"s_max": 0.57}, sigmas={"s_max": math.inf}, truth={"levels_n": [0.5, 5.0, 25.0]},
              equivalent=("s_max",), key_unidentified=())
    back = CaseResult.from_json(r.to_json())
    assert back == r and back.sigmas["s_max"] == math.inf and isinstance(back.names, tuple)


def test_timing_judges_each_effect_on_its_own_goal_by_wall_and_cpu_time(tmp_path):
    assert time_goal("interface_softening") == time_goal("softening_joint") == 45.0
    assert time_goal("none") == time_goal("interface_joint") == 30.0
    log = tmp_path / "cases.jsonl.gz"
    cases = [_case("interface_softening", 60.0, 44.0), _case("none", 20.0, 31.0, named="none")]
    with gzip.open(log, "wt", encoding="utf-8") as fh:
        fh.write("".join(c.to_json() + "\n" for c in cases))
    bench = BenchResult.from_file(str(log))
    assert bench.cases == cases and bench.seconds == pytest.approx(80.0)
    rows = {r["effect"]: r for r in bench.timing()}
    # 60 s wall > 45 s goal, 44 s CPU <= 45 s; 20 s wall <= 30 s, 31 s CPU > 30 s
    assert (rows["interface_softening"]["wall_met"], rows["interface_softening"]["cpu_met"]) == ("NO", "yes")
    assert (rows["none"]["wall_met"], rows["none"]["cpu_met"]) == ("yes", "NO")
    assert rows["none"]["load_1min"] == "3.5–3.5"


def test_unknown_effects_are_named():
    assert effects_from("gain,,delay") == ["gain", "delay"]
    with pytest.raises(ValueError, match=r"unknown gian; known: none, "):
        effects_from("gain,gian")
