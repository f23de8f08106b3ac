"""`planthub compare`: real runs judged against a golden one — equal runs pass, a changed setting fails
naming its signals, times and deviations and drawing them, a time shift within --time-shift passes —
and every way the command refuses, by its message; the band and the matching as functions of arrays.

    bottle ──► [============= belt (2 m, 0.5 m/s) =====|barrier|=====]     (belt_bottle_sensor.yaml)
    recorded: bottle.body.position, bottle.body.velocity (x, y, z), barrier.trigger.occupied (bool),
              barrier.trigger.object (string); logged: barrier.trigger.on_enter, on_leave
"""
from __future__ import annotations

import csv
import re
import shutil

import numpy as np
import pytest
from PIL import Image

from hub.core.errors import PlanthubError
from hub.reports.compare import band, compare, held_within, match_events, resample, window_min
from hub.reports.compare_plots import plot_failures

from .helpers import ROOT, planthub, run_scenario

SCENARIO = ROOT / "scenarios" / "belt_bottle_sensor.yaml"
RECORD = ["bottle.body.position", "bottle.body.velocity", "barrier.trigger.occupied", "barrier.trigger.object"]
SIGNALS = 10   # 8 recorded columns and 2 event slots


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Run folders of belt_bottle_sensor (3.5 s, 150 Hz): the golden one, the same again, and changed ones."""
    root = tmp_path_factory.mktemp("compare")
    variants = {"golden": {}, "again": {}, "faster": {"objects.belt.speed": 0.55},
                "finer": {"run.physics_rate": 300}, "short": {"run.duration": 2},
                "fewer": {"record": ["bottle.body.position", "barrier.trigger.occupied", "barrier.trigger.object"]}}
    for name, changes in variants.items():
        run_scenario(SCENARIO, root / name, {"record": RECORD, **changes})
    return root


def planthub_compare(capsys, *args):
    """`planthub compare ARGS` in this process: (exit code, stdout, stderr)."""
    return planthub(capsys, "compare", *args)


def line_of(out: str, name: str) -> str:
    return next(line for line in out.splitlines() if line.startswith(f"  ✓ {name} —") or line.startswith(f"  ✗ {name} —"))


def is_png(path) -> bool:
    with Image.open(path) as image:
        image.verify()
        return image.format == "PNG"


def events_of(folder):
    with open(folder / "events.csv", newline="") as handle:
        return {row["slot"]: float(row["time"]) for row in csv.DictReader(handle)}


def test_two_runs_of_one_scenario_pass(runs, capsys):
    code, out, err = planthub_compare(capsys, runs / "again", runs / "golden")
    assert code == 0, out + err
    lines = out.splitlines()
    assert lines[0] == (f"planthub compare {runs / 'again'} against {runs / 'golden'}  (t = 0–3.5 s; "
                        "band 1e-06 + 0.001·|ref|; time shift 0 s)")
    assert lines[1] == "  ✓ bottle.body.position.x — equal at all 526 points"
    assert line_of(out, "barrier.trigger.on_enter") == \
        "  ✓ barrier.trigger.on_enter — 1 of 1 reference event matched at the same time"
    assert len(lines) == 1 + SIGNALS + 1 and all(line.startswith("  ✓ ") for line in lines[1:-1])
    assert lines[-1] == f"{SIGNALS} signals passed, 0 failed"
    assert not (runs / "again" / "compare").exists()   # nothing failed, nothing drawn


def test_a_faster_belt_fails_naming_the_signals_their_times_and_deviations_and_draws_them(runs, capsys):
    code, out, err = planthub_compare(capsys, runs / "faster", runs / "golden")
    assert code == 1, out + err
    result = compare(runs / "faster", runs / "golden")   # the library a benchmark calls
    x = result.signal("bottle.body.position.x")
    # 0.05 m/s faster for 3.5 s: the bottle is some 0.17 m further along at the end, and ever more so.
    assert not x.passed and 0.15 < x.max_deviation < 0.2 and x.at_time == 3.5
    assert x.rms < x.max_deviation and x.first_out < 0.1 and x.out_of_band > 500 and x.points == 526
    assert line_of(out, "bottle.body.position.x") == (
        f"  ✗ bottle.body.position.x — {x.out_of_band} of 526 points out of band from {x.first_out:g} s on; "
        f"max deviation {x.max_deviation:.4g} at 3.5 s, rms {x.rms:.4g}, up to {x.excess:.4g} outside the band")
    assert result.signal("bottle.body.position.y").passed   # across the belt nothing changes
    enter = events_of(runs / "golden")["barrier.trigger.on_enter"]
    early = events_of(runs / "faster")["barrier.trigger.on_enter"]
    assert line_of(out, "barrier.trigger.on_enter") == (
        f"  ✗ barrier.trigger.on_enter — 0 of 1 reference event matched; missing: {enter:g} s (bottle); "
        f"extra in the run: {early:g} s (bottle)")
    assert line_of(out, "barrier.trigger.object") == \
        f"  ✗ barrier.trigger.object — {result.signal('barrier.trigger.object').out_of_band} of 526 points " \
        f"differ from {early:g} s on"
    failing = [v.name for v in result.failed]
    assert {"bottle.body.position.x", "bottle.body.velocity.x", "barrier.trigger.occupied",
            "barrier.trigger.object", "barrier.trigger.on_enter", "barrier.trigger.on_leave"} <= set(failing)
    assert out.splitlines()[-1] == f"{SIGNALS - len(failing)} signals passed, {len(failing)} failed"
    drawn = sorted((runs / "faster" / "compare").iterdir())
    assert [p.name for p in drawn] == sorted(f"{name}.png" for name in failing)
    assert all(is_png(p) for p in drawn)
    assert f"      plot: {runs / 'faster' / 'compare' / 'bottle.body.position.x.png'}" in out.splitlines()


def test_a_plot_left_from_an_earlier_comparison_goes_when_its_signal_passes(runs, tmp_path):
    failed = plot_failures(compare(runs / "faster", runs / "golden", slots=["bottle.body.position.x"]), tmp_path)
    assert failed == [tmp_path / "bottle.body.position.x.png"] and is_png(failed[0])
    assert plot_failures(compare(runs / "golden", runs / "golden", slots=["bottle.body.position.x"]), tmp_path) == []
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("within", [False, True])
def test_events_and_states_shifted_in_time_pass_within_time_shift_only(runs, capsys, within):
    golden, faster = events_of(runs / "golden"), events_of(runs / "faster")
    shifts = {slot: faster[slot] - golden[slot] for slot in golden}
    largest = max(shifts.values(), key=abs)
    assert largest < -0.1   # the faster belt brings the bottle to the barrier well before
    shift = abs(largest) + 0.02 if within else abs(largest) / 2
    code, out, err = planthub_compare(capsys, runs / "faster", runs / "golden", "--slots", "barrier.*",
                                      "--time-shift", shift)
    names = ["barrier.trigger.occupied", "barrier.trigger.object", "barrier.trigger.on_enter",
             "barrier.trigger.on_leave"]
    assert [line.split(" — ")[0][4:] for line in out.splitlines()[1:] if line.startswith("  ")
            and not line.startswith("      ")] == names   # --slots picks the recorded and the logged alike
    if within:
        assert code == 0, out
        enter = shifts["barrier.trigger.on_enter"]
        assert line_of(out, "barrier.trigger.on_enter") == (
            f"  ✓ barrier.trigger.on_enter — 1 of 1 reference event matched, the largest shift {abs(enter):.4g} s "
            f"earlier in the run (the reference's at {golden['barrier.trigger.on_enter']:g} s)")
        assert out.splitlines()[-1] == "4 signals passed, 0 failed"
    else:
        assert code == 1
        assert line_of(out, "barrier.trigger.on_leave").startswith("  ✗ barrier.trigger.on_leave — 0 of 1 reference "
                                                                   "event matched; missing:")
        assert out.splitlines()[-1] == "0 signals passed, 4 failed"


def test_a_finer_reference_grid_has_the_run_interpolated_onto_it(runs, capsys):
    coarse_on_fine = compare(runs / "golden", runs / "finer")
    assert coarse_on_fine.resampled and coarse_on_fine.signal("bottle.body.position.x").points == 1051
    fine_on_coarse = compare(runs / "finer", runs / "golden")   # the run has every point of the reference
    assert not fine_on_coarse.resampled and fine_on_coarse.signal("bottle.body.position.x").points == 526
    code, out, err = planthub_compare(capsys, runs / "golden", runs / "finer", "--slots", "bottle.body.position",
                                      "--atol", "0.01")
    assert code == 0, out + err   # 150 Hz and 300 Hz carry the bottle alike to within a centimetre
    assert out.splitlines()[0].endswith("; the run's 526 points interpolated onto the reference's 1051)")


def test_range_tol_widens_the_band_by_a_share_of_the_reference_signals_range(runs):
    point = compare(runs / "golden", runs / "finer", slots=["bottle.body.position.x"]).signal("bottle.body.position.x")
    wide = compare(runs / "golden", runs / "finer", slots=["bottle.body.position.x"], range_tol=0.01)
    wide = wide.signal("bottle.body.position.x")
    x = point.trace.reference
    assert np.allclose((wide.trace.upper - wide.trace.lower) - (point.trace.upper - point.trace.lower),
                       2 * 0.01 * (x.max() - x.min()))
    assert wide.passed and wide.max_deviation == point.max_deviation   # the deviation is the band's business


def test_a_run_that_ends_early_fails_and_passes_up_to_its_end(runs, capsys):
    code, out, _ = planthub_compare(capsys, runs / "short", runs / "golden")
    assert code == 1
    assert "  ✗ the run ends at 2 s, before the reference's 3.5 s: its signals are judged up to there" in out
    assert line_of(out, "bottle.body.position.x") == "  ✓ bottle.body.position.x — equal at all 301 points"
    assert "on_enter" not in out   # the bottle reaches the barrier after 2 s: not missing, not judged
    assert out.splitlines()[-1] == "8 signals passed, 0 failed; 1 problem"
    code, out, _ = planthub_compare(capsys, runs / "short", runs / "golden", "--to", 2)
    assert code == 0, out


def test_a_signal_the_run_does_not_record_fails_and_one_only_the_run_records_is_told(runs, capsys):
    code, out, _ = planthub_compare(capsys, runs / "fewer", runs / "golden")
    assert code == 1
    assert line_of(out, "bottle.body.velocity.z") == \
        f"  ✗ bottle.body.velocity.z — not in the run's recording ({runs / 'fewer' / 'recording.csv'})"
    assert out.splitlines()[-1] == f"{SIGNALS - 3} signals passed, 3 failed"
    code, out, err = planthub_compare(capsys, runs / "golden", runs / "fewer")
    assert code == 0, out
    assert err == ("planthub compare: not compared, recorded by the run only: bottle.body.velocity.x, "
                   "bottle.body.velocity.y, bottle.body.velocity.z\n")


@pytest.mark.parametrize("args, message", [
    (["{tmp}/nowhere", "{runs}/golden"], "RUN {tmp}/nowhere: no such folder (give the run folder `planthub run --out "
                                        "DIR` wrote)"),
    (["{runs}/golden", "{runs}"], "REFERENCE {runs} is not a run folder: it holds none of recording.csv, events.csv, "
                                  "summary.json (what `planthub run --out DIR` writes); run folders in it: "),
    (["{runs}/golden/recording.csv", "{runs}/golden"], "RUN {runs}/golden/recording.csv is a file, not a run folder: "
                                                      "give its folder, {runs}/golden"),
    (["{runs}/again", "{runs}/golden", "--slots", "bottle.body.possition", "sink.*"],
     "--slots: neither recorded nor logged: 'bottle.body.possition' (did you mean 'bottle.body.position'?); no "
     "recorded or logged slot matches 'sink.*'. {runs}/golden/recording.csv records bottle.body.position, "
     "bottle.body.velocity, barrier.trigger.occupied, barrier.trigger.object; the event logs name "
     "barrier.trigger.on_enter, barrier.trigger.on_leave"),
    (["{runs}/again", "{runs}/golden", "--slots", "barrier.trigger.on_entr"],
     "(did you mean 'barrier.trigger.on_enter'?)"),
    (["{runs}/again", "{runs}/golden", "--from", 3, "--to", 2], "--from 3 s is not before --to 2 s"),
    (["{runs}/again", "{runs}/golden", "--from", 4], "--from 4 s is after the end of the reference, "
                                                    "{runs}/golden/recording.csv (3.5 s)"),
    (["{runs}/again", "{runs}/golden", "--out", "{runs}/golden/summary.json"],
     "--out {runs}/golden/summary.json is a file, not a folder for the PNGs"),
])
def test_bad_input_is_a_usage_error_that_says_what_is_wrong(runs, capsys, tmp_path, args, message):
    args = [str(a).format(runs=runs, tmp=tmp_path) for a in args]
    code, out, err = planthub_compare(capsys, *args)
    assert code == 2 and out == ""
    assert message.format(runs=runs, tmp=tmp_path) in err


@pytest.mark.parametrize("option, value", [("--rtol", "-1"), ("--atol", "nan"), ("--time-shift", "soon")])
def test_a_tolerance_that_is_no_number_or_negative_is_refused_by_argparse(runs, capsys, option, value):
    code, _, err = planthub_compare(capsys, runs / "again", runs / "golden", option, value)
    assert code == 2
    assert f"argument {option}: expected a " in err and repr(value) in err


def test_a_broken_recording_is_named_by_its_file_and_line(runs, capsys, tmp_path):
    broken = tmp_path / "broken"
    shutil.copytree(runs / "golden", broken)
    lines = (broken / "recording.csv").read_text().splitlines(keepends=True)
    lines[4] = "soon" + lines[4][lines[4].index(","):]
    (broken / "recording.csv").write_text("".join(lines))
    code, _, err = planthub_compare(capsys, broken, runs / "golden")
    assert code == 1
    assert err == f"planthub: {broken / 'recording.csv'}:5: the time 'soon' is not a number\n"


def test_the_library_refuses_an_unknown_name_and_a_negative_tolerance(runs):
    with pytest.raises(PlanthubError, match=re.escape("'bottle.body.position' is neither a column of")):
        compare(runs / "again", runs / "golden", slots=["bottle.body.position"])   # exact names: SLOT.x
    with pytest.raises(PlanthubError, match="rtol must be a finite number ≥ 0, not -0.1"):
        compare(runs / "again", runs / "golden", rtol=-0.1)


# --- the pieces, on arrays ------------------------------------------------------------------------

def test_a_step_one_sample_late_leaves_the_band_unless_the_time_shift_spans_it():
    t = np.arange(6.0)
    ref, late = np.array([0, 0, 1, 1, 1, 1.0]), np.array([0, 0, 0, 1, 1, 1.0])
    lower, upper = band(t, ref, rtol=0.0, atol=0.1)
    assert list((late < lower) | (late > upper)) == [False, False, True, False, False, False]
    lower, upper = band(t, ref, rtol=0.0, atol=0.1, shift=1.0)
    assert not ((late < lower) | (late > upper)).any()
    assert list(lower) == [-0.1, -0.1, -0.1, 0.9, 0.9, 0.9] and list(upper) == [0.1, 1.1, 1.1, 1.1, 1.1, 1.1]
    # between grid points, the reference's value at t ± shift counts: a ramp half a sample late passes
    lower, upper = band(t, t.copy(), rtol=0.0, atol=0.0, shift=0.5)
    assert np.allclose(lower[1:], t[1:] - 0.5) and np.allclose(upper[:-1], t[:-1] + 0.5)
    assert lower[0] == 0.0 and upper[-1] == 5.0   # not before the reference's start, nor after its end
    assert list(held_within(t, ref, late, 0.0)) == [True, True, False, True, True, True]
    assert held_within(t, ref, late, 1.0).all() and not held_within(t, ref, np.full(6, 2.0), 5.0).any()


def test_the_window_minimum_equals_the_one_taken_point_by_point():
    rng = np.random.default_rng(0)
    values = rng.normal(size=300)
    a = rng.integers(0, 300, size=300)
    b = np.minimum(a + rng.integers(1, 80, size=300), 300)
    assert np.array_equal(window_min(values, a, b), [values[i:j].min() for i, j in zip(a, b)])


def test_resampling_is_linear_for_reals_and_held_for_states():
    t_from, t_to = np.array([0.0, 1.0, 2.0]), np.array([0.0, 0.5, 1.0, 1.75])
    assert list(resample(t_from, np.array([0.0, 2.0, 0.0]), t_to, held=False)) == [0.0, 1.0, 2.0, 0.5]
    assert list(resample(t_from, np.array([0.0, 1.0, 0.0]), t_to, held=True)) == [0.0, 0.0, 1.0, 1.0]


def test_events_are_matched_one_to_one_within_the_shift():
    # 1.0 could take 1.1 or 0.95; taking the earliest leaves 1.1 for 1.2, so all three match
    assert match_events([1.0, 1.2, 5.0], [0.95, 1.1, 5.3], 0.15) == ([(0, 0), (1, 1)], [2], [2])
    assert match_events([1.0, 1.0], [1.0], 0.0) == ([(0, 0)], [1], [])
    assert match_events([], [2.0], 1.0) == ([], [], [0])
