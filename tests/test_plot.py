"""`planthub plot`: a PNG of a real run's recorded slots, and every way the command refuses, by its message."""
from __future__ import annotations

import shutil
import subprocess
import sys

import pytest
from PIL import Image, ImageChops

from .helpers import ROOT, planthub

#   barrier.trigger.on_enter ──► stop.value.set, stop.value.out (false) ──► belt.drive.run
#   recorded: bottle.body.position (x, y, z), belt.drive.running, barrier.trigger.on_enter
SCENARIO = "scenarios/stop_at_barrier.yaml"
RECORDED = "It records: bottle.body.position (x, y, z), belt.drive.running, barrier.trigger.on_enter"
WIDE, TALL = 1000, 240   # px of the PNG, and of each panel (hub/cli/plot.py: WIDTH, PANEL_HEIGHT at 100 dpi)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """A run folder of 3 s of stop_at_barrier, written by the real command line."""
    out = tmp_path_factory.mktemp("plot") / "stop"
    proc = subprocess.run([sys.executable, "-m", "hub", "run", SCENARIO, "--out", str(out), "--set", "run.duration=3"],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    return out


def plot(capsys, *args):
    """`planthub plot ARGS` in this process: (exit code, stdout, stderr)."""
    return planthub(capsys, "plot", *args)


def png(path):
    with Image.open(path) as image:
        assert image.format == "PNG"
        image.verify()
    with Image.open(path) as image:   # verify() leaves the image unusable
        return image.convert("RGB")


def test_the_command_line_writes_plot_png_into_the_run_folder_and_prints_its_path(run):
    (run / "plot.png").unlink(missing_ok=True)
    proc = subprocess.run([sys.executable, "-m", "hub", "plot", str(run), "bottle.body.position", "belt.drive.running"],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == f"{run / 'plot.png'}\n"
    assert proc.stderr == ("planthub plot: 2 panels (bottle.body.position, belt.drive.running), t = 0–3 s, "
                           "151 points\n")
    assert png(run / "plot.png").size == (WIDE, 2 * TALL)


def test_two_slots_draw_different_pixels(run, capsys, tmp_path):
    for slot in ("bottle.body.position.x", "belt.drive.running"):
        code, out, err = plot(capsys, run, slot, "--out", tmp_path / f"{slot}.png")
        assert code == 0, err
        assert out == f"{tmp_path / f'{slot}.png'}\n"
    position, running = (png(tmp_path / f"{slot}.png") for slot in ("bottle.body.position.x", "belt.drive.running"))
    assert position.size == running.size == (WIDE, TALL)
    changed = ImageChops.difference(position, running).convert("L").point(lambda v: 255 if v else 0)
    assert changed.histogram()[255] > 1000   # whole curves apart, not a pixel of anti-aliasing


def test_a_vec3_is_one_panel_of_its_components_and_a_glob_picks_several(run, capsys, tmp_path):
    code, _, err = plot(capsys, run, "bottle.body.position.[xy]", "bottle.body.position.z", "--out", tmp_path / "p.png")
    assert code == 0, err
    assert "1 panel (bottle.body.position)" in err
    assert png(tmp_path / "p.png").size == (WIDE, TALL)
    code, _, err = plot(capsys, run, "b*", "--out", tmp_path / "b.png")   # a glob matches across the dots
    assert code == 0, err
    assert "3 panels (bottle.body.position, belt.drive.running, barrier.trigger.on_enter)" in err
    assert png(tmp_path / "b.png").size == (WIDE, 3 * TALL)
    code, _, err = plot(capsys, run, "bottle.position", "-q", "--out", tmp_path / "short.png")   # object.slot
    assert code == 0 and err == ""


def test_from_and_to_narrow_the_time_axis(run, capsys, tmp_path):
    code, _, err = plot(capsys, run, "belt.drive.running", "--from", "1", "--to", "2", "--out", tmp_path / "w.png")
    assert code == 0, err
    assert err == "planthub plot: 1 panel (belt.drive.running), t = 1–2 s, 51 points\n"
    code, _, _ = plot(capsys, run, "belt.drive.running", "--out", tmp_path / "all.png")
    assert ImageChops.difference(png(tmp_path / "w.png"), png(tmp_path / "all.png")).getbbox() is not None


def test_events_mark_their_times_and_a_pattern_that_matches_none_is_told(run, capsys, tmp_path):
    code, _, err = plot(capsys, run, "belt.drive.running", "--events", "barrier.*", "--out", tmp_path / "e.png")
    assert code == 0, err
    plot(capsys, run, "belt.drive.running", "--out", tmp_path / "plain.png")
    assert ImageChops.difference(png(tmp_path / "e.png"), png(tmp_path / "plain.png")).getbbox() is not None
    code, _, err = plot(capsys, run, "belt.drive.running", "--events", "barrier.trigger.on_entr", "--out",
                        tmp_path / "n.png")
    assert code == 0
    assert err.startswith(f"planthub plot: warning: --events 'barrier.trigger.on_entr': no event in "
                          f"{run / 'events.csv'} matches (did you mean 'barrier.trigger.on_enter'?); it logs "
                          "barrier.trigger.on_enter\n")


# --- what it refuses: the file and the cause, never a traceback -------------------------------


def test_a_missing_folder(capsys, tmp_path):
    code, out, err = plot(capsys, tmp_path / "nowhere", "belt.drive.running")
    assert (code, out) == (2, "")
    assert err == (f"planthub: {tmp_path / 'nowhere'}: no such folder (give the run folder `planthub run --out DIR` "
                   "wrote)\n")


def test_a_file_instead_of_the_run_folder(run, capsys):
    code, _, err = plot(capsys, run / "recording.csv", "belt.drive.running")
    assert code == 2
    assert err == f"planthub: {run / 'recording.csv'} is a file, not a run folder: give its folder, {run}\n"


def test_a_folder_that_is_no_run_folder_names_the_run_folders_in_it(run, capsys, tmp_path):
    code, _, err = plot(capsys, tmp_path, "belt.drive.running")
    assert code == 2
    assert err == (f"planthub: {tmp_path} is not a run folder: it holds none of recording.csv, events.csv, "
                   "summary.json (what `planthub run --out DIR` writes)\n")
    code, _, err = plot(capsys, run.parent, "belt.drive.running")
    assert code == 2
    assert err.endswith(f"(what `planthub run --out DIR` writes); run folders in it: {run}\n")


def test_a_run_folder_without_its_recording(run, capsys, tmp_path):
    for name in ("events.csv", "summary.json"):
        shutil.copy(run / name, tmp_path / name)
    code, _, err = plot(capsys, tmp_path, "belt.drive.running")
    assert code == 2
    assert err == (f"planthub: {tmp_path / 'recording.csv'}: no such file (the run folder holds only events.csv, "
                   "summary.json)\n")


def test_a_slot_not_recorded_lists_the_recorded_ones_with_a_did_you_mean(run, capsys):
    code, out, err = plot(capsys, run, "bottle.body.positon", "sink_*.count.total", "belt.drive.running")
    assert (code, out) == (2, "")
    assert err == (f"planthub: {run / 'recording.csv'}: not recorded: 'bottle.body.positon' (did you mean "
                   f"'bottle.body.position'?); no recorded slot matches 'sink_*.count.total'. {RECORDED}\n")
    code, _, err = plot(capsys, run, "stopper.gate.closed")
    assert err == f"planthub: {run / 'recording.csv'}: not recorded: 'stopper.gate.closed'. {RECORDED}\n"


@pytest.mark.parametrize("text, cause", [
    ("", "is empty: not even its header (the run wrote nothing)"),
    ('"time","belt.drive.running"\n', "is empty: its header, but no recorded point (the run ended before its "
                                      "first communication point)"),
    ('"time"\n0.0\n', "records no slot, only the time: the scenario has no `record:` list"),
    ('"t","belt.drive.running"\n0.0,1\n', "is not a planthub recording: its first column is 't', not 'time'"),
])
def test_an_empty_or_foreign_recording(capsys, tmp_path, text, cause):
    (tmp_path / "recording.csv").write_text(text)
    code, _, err = plot(capsys, tmp_path, "belt.drive.running")
    assert code == 1
    assert err == f"planthub: {tmp_path / 'recording.csv'} {cause}\n"


def test_a_broken_row_is_named_by_its_line_and_a_last_line_cut_short_is_left_out(capsys, tmp_path):
    recording = tmp_path / "recording.csv"
    recording.write_text('"time","belt.drive.running"\n0.0,1\n0.02\n0.04,0\n')
    code, _, err = plot(capsys, tmp_path, "belt.drive.running")
    assert code == 1
    assert err == f"planthub: {recording}:3: 1 columns, but its header names 2\n"
    recording.write_text('"time","belt.drive.running"\n0.0,1\n0.02,0\n0.0')   # a run killed while writing
    code, out, err = plot(capsys, tmp_path, "belt.drive.running")
    assert code == 0, err
    assert out == f"{tmp_path / 'plot.png'}\n"
    assert err.startswith(f"planthub plot: warning: {recording}:4: the last line is cut short (1 of 2 columns); "
                          "drawn without it\n")


@pytest.mark.parametrize("args, message", [
    (["--from", "abc"], "planthub plot: error: argument --from: expected a time in seconds, got 'abc'"),
    (["--to", "nan"], "planthub plot: error: argument --to: expected a finite time in seconds, got 'nan'"),
    (["--from", "2", "--to", "1"], "planthub: --from 2 s is not before --to 1 s"),
    (["--from", "9"], "planthub: --from 9 s is after the end of {recording} (3 s)"),
    (["--to", "-1"], "planthub: --to -1 s is before the start of {recording} (0 s)"),
    (["--from", "1.001", "--to", "1.002"],
     "planthub: no recorded point between --from 1.001 s and --to 1.002 s in {recording} (points from 0 to 3 s)"),
    (["--out", "plot.svg"], "planthub: --out plot.svg: planthub plot writes a PNG, so name a .png file"),
])
def test_a_bad_window_or_output_is_a_usage_error(run, capsys, args, message):
    code, out, err = plot(capsys, run, "belt.drive.running", *args)
    assert (code, out) == (2, "")
    assert err.splitlines()[-1] == message.format(recording=run / "recording.csv")


def test_events_without_an_event_log(run, capsys, tmp_path):
    shutil.copy(run / "recording.csv", tmp_path / "recording.csv")
    code, _, err = plot(capsys, tmp_path, "belt.drive.running", "--events", "barrier.*")
    assert code == 2
    assert err == f"planthub: {tmp_path / 'events.csv'}: no such file, so --events has no events to mark\n"


def test_an_output_beside_a_file_or_too_many_panels(run, capsys, tmp_path):
    (tmp_path / "taken").write_text("")
    code, _, err = plot(capsys, run, "belt.drive.running", "--out", tmp_path / "taken" / "p.png")
    assert code == 2
    assert err == f"planthub: --out {tmp_path / 'taken' / 'p.png'}: {tmp_path / 'taken'} is a file, not a folder\n"
    many = tmp_path / "many"
    many.mkdir()
    names = [f"sink_{i}.count.total" for i in range(41)]
    (many / "recording.csv").write_text(",".join(["time", *names]) + "\n" + ",".join(["0.0"] + ["0"] * 41) + "\n")
    code, _, err = plot(capsys, many, "sink_*.count.total")
    assert code == 2
    assert err.startswith(f"planthub: 41 slots picked from {many / 'recording.csv'} (sink_0.count.total, ")
    assert err.endswith(", … (41 in all)): at most 40 panels fit in one plot; name fewer\n")


@pytest.mark.parametrize("log, cause", [
    ("", "{log} is empty: not even its header"),
    ("when,what\n", "{log} is not a planthub event log: its header names no time and slot columns"),
    ("time,tick,slot,detail\nsoon,1,barrier.trigger.on_enter,bottle\n", "{log}:2: the time 'soon' is not a number"),
])
def test_a_broken_event_log(run, capsys, tmp_path, log, cause):
    shutil.copy(run / "recording.csv", tmp_path / "recording.csv")
    (tmp_path / "events.csv").write_text(log)
    code, _, err = plot(capsys, tmp_path, "belt.drive.running", "--events", "barrier.*")
    assert code == 1
    assert err == "planthub: " + cause.format(log=tmp_path / "events.csv") + "\n"


def test_a_recording_that_is_no_text(capsys, tmp_path):
    (tmp_path / "recording.csv").write_bytes(b'"time","a.b.c"\n0.0,\xff\n')
    code, _, err = plot(capsys, tmp_path, "a.b.c")
    assert code == 1
    assert err.startswith(f"planthub: {tmp_path / 'recording.csv'} is not a CSV file planthub wrote: 'utf-8' codec "
                          "can't decode byte 0xff")
