"""Issue 26, items 1-3: nothing destroyed, nothing started from a wrong state.

1. ``--overwrite`` decides everything before it removes anything (a refusal changes nothing);
2. ``--init-from`` verifies ``run.json`` and the rows as a resume does;
3. a resume replays the end of the orbit with the recorded map and compares bit for bit: a checkpoint moved by one
   ulp or one step, a CSV declared shorter than its rows, a map parameter changed by 1e-12 are refused, and an
   unedited run still resumes to exactly the uninterrupted orbit.

Every edit of ``run.json`` below recomputes its SHA-256 digest (``write_run``), as anyone editing the file would:
the refusals come from the data, not from the digest.  References are one uninterrupted ``iterate`` call, compared
with ``np.array_equal`` (the run layer promises bit-identical resumes)."""

from __future__ import annotations

import copy
import hashlib
import os
import signal

import h5py
import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import run as rl
from jetgaudin.run.files import write_run
from test_run import run_cli

from conftest import APPENDIX2_B, APPENDIX2_ETA, APPENDIX2_X0

X0 = np.array(APPENDIX2_X0)


def one_line(err: str) -> bool:
    return len([ln for ln in err.splitlines() if ln.strip()]) == 1 and "Traceback" not in err


def two_point(kernel="numpy", b=APPENDIX2_B, eta=APPENDIX2_ETA):
    return jg.TwoPointBacklund(b, eta, backend=kernel)


def interrupt_at(out, m, X, steps, every, at, program="jetgaudin orbit"):
    """Run ``m`` from ``X`` for ``steps`` steps into ``out`` and stop it by a real SIGINT once step ``at`` is passed
    (sent from the progress callback: the driver stops after the current kernel call); returns ``run.json``."""
    def progress(n, _total):
        if n >= at:
            os.kill(os.getpid(), signal.SIGINT)

    spec = rl.RunSpec(m, X, steps, every, checkpoint_seconds=0.0, program=program)
    with pytest.raises(rl.RunInterrupted):
        rl.start(spec, out, progress=progress, max_chunk_steps=3)
    run = rl.read_run(out)
    assert run["status"] == "interrupted"
    return run


# --------------------------------------------------------------------------------------------- item 1
def test_overwrite_of_a_directory_with_a_subdirectory_removes_nothing(tmp_path, capsys):
    d = tmp_path / "D"
    d.mkdir()
    for f in "abcdefgh":
        (d / f"{f}.txt").write_text(f)
    (d / "sub").mkdir()
    code, _, err = run_cli(capsys, "orbit", "--out", d, "--overwrite", "--steps", 3, "--no-plots")
    assert code == 2 and one_line(err) and "sub" in err
    assert sorted(p.name for p in d.iterdir()) == [f"{f}.txt" for f in "abcdefgh"] + ["sub"]
    assert all((d / f"{f}.txt").read_text() == f for f in "abcdefgh")


def test_overwrite_of_a_completed_run_with_a_subfolder_changes_nothing(tmp_path, capsys):
    d = tmp_path / "run"
    assert run_cli(capsys, "orbit", "--out", d, "--steps", 5, "--no-plots")[0] == 0
    (d / "notes").mkdir()
    before = {p.name: p.read_bytes() for p in d.iterdir() if p.is_file()}
    code, _, err = run_cli(capsys, "orbit", "--out", d, "--overwrite", "--steps", 3, "--no-plots")
    assert code == 2 and one_line(err)
    assert {p.name: p.read_bytes() for p in d.iterdir() if p.is_file()} == before  # orbit.h5 kept, run.json too
    assert rl.read_run(d, verify=True)["status"] == "completed"


# --------------------------------------------------------------------------------------------- item 2
@pytest.fixture
def source(tmp_path, capsys):
    a = tmp_path / "a"
    assert run_cli(capsys, "orbit", "--steps", 10, "--kernel", "numpy", "--no-plots", "--out", a)[0] == 0
    return a


def _flip_last_row(path):
    with h5py.File(path, "r+") as f:
        x = f["X"][-1]
        x[0] = np.nextafter(x[0], np.inf)  # one bit of one double
        f["X"][-1] = x


@pytest.mark.parametrize("command", ["orbit", "ensemble"])
@pytest.mark.parametrize("damage", ["flipped bit in the last row", "rows edited", "rows edited, digest recomputed"])
def test_init_from_refuses_a_state_it_cannot_verify(source, tmp_path, capsys, command, damage):
    if damage.startswith("flipped"):
        _flip_last_row(source / "orbit.h5")
    else:
        run = rl.read_run(source)
        run["checkpoint"]["rows"] -= 1
        if damage.endswith("recomputed"):
            write_run(source, run)
        else:
            text = (source / "run.json").read_text().replace('"rows": 11', '"rows": 10')
            assert text != (source / "run.json").read_text()
            (source / "run.json").write_text(text)
    extra = ["--no-plots"] if command == "orbit" else ["--no-progress"]
    code, _, err = run_cli(capsys, command, "--init-from", source, "--steps", 3, "--out", tmp_path / "b", *extra)
    assert code == 2 and one_line(err), err
    assert not (tmp_path / "b").exists()


# --------------------------------------------------------------------------------------------- item 3
EVERY, STEPS, AT = 7, 60, 37  # interrupted at 37 or 38: between the saved rows 35 and 42


@pytest.fixture(params=["numpy", "compiled"])
def off_grid(request, tmp_path):
    out = tmp_path / "r"
    run = interrupt_at(out, two_point(request.param), X0, STEPS, EVERY, AT)
    assert run["checkpoint"]["step"] % EVERY != 0  # off the save grid: the case a digest alone cannot protect
    return out, run, request.param


def test_an_unedited_off_grid_checkpoint_resumes_bit_for_bit(off_grid):
    out, _, kernel = off_grid
    rl.resume(out)
    d = rl.load(out)
    assert np.array_equal(d.n, np.r_[np.arange(0, STEPS, EVERY), STEPS])  # the grid and the last step
    ref = two_point(kernel).iterate(X0, STEPS)[d.n]
    assert np.array_equal(d.X, ref)
    n, X = rl.read_csv(out / "orbit.csv")
    assert np.array_equal(X, ref) and np.array_equal(n, d.n)


def _edit(run, what):
    ck = run["checkpoint"]
    if what == "state by one ulp":
        ck["X_hex"][4] = np.nextafter(float.fromhex(ck["X_hex"][4]), np.inf).hex()
    elif what == "nu1 by one ulp":
        ck["nu1_hex"][1] = np.nextafter(float.fromhex(ck["nu1_hex"][1]), np.inf).hex()
    elif what == "step + 1":
        ck["step"] += 1
        run["last_safe_step"] = ck["step"]
    elif what == "step - 1":
        ck["step"] -= 1
        run["last_safe_step"] = ck["step"]
    elif what == "csv_bytes = 0":
        ck["csv_bytes"], ck["csv_sha256"] = 0, hashlib.sha256().hexdigest()
    elif what == "eta by 1e-12":
        run["map"]["eta"][1] *= 1 + 1e-12
        run["inputs"]["eta"][1] *= 1 + 1e-12
    elif what == "b by 1e-12":
        run["map"]["b"] *= 1 + 1e-12
        run["inputs"]["b"] *= 1 + 1e-12
    elif what == "save_every":
        run["inputs"]["save_every"] = EVERY + 1
    elif what == "kernel":
        k = "numpy" if run["map"]["backend"] == "compiled" else "compiled"
        run["map"]["backend"] = run["inputs"]["kernel"] = k
    elif what == "anchor by one ulp":
        ck["anchor"]["X_hex"][0] = np.nextafter(float.fromhex(ck["anchor"]["X_hex"][0]), -np.inf).hex()
    elif what == "anchor removed":
        del ck["anchor"]
    return run


EDITS = ["state by one ulp", "nu1 by one ulp", "step + 1", "step - 1", "csv_bytes = 0", "eta by 1e-12", "b by 1e-12",
         "save_every", "kernel", "anchor by one ulp", "anchor removed"]


@pytest.mark.parametrize("what", EDITS)
def test_an_edited_checkpoint_or_map_is_refused_by_replay(off_grid, what):
    out, run, _ = off_grid
    write_run(out, _edit(copy.deepcopy(run), what))  # a valid digest: what an editor produces
    files = {p.name: p.read_bytes() for p in out.iterdir() if p.name.endswith((".h5", ".csv"))}
    with pytest.raises(jg.RecordingError, match="cannot resume"):
        rl.resume(out)
    # a refused resume never shortens a durable file
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.name.endswith((".h5", ".csv"))}.keys() == files.keys()
    assert (out / "orbit.csv").read_bytes() == files["orbit.csv"]


def test_a_map_edit_is_refused_when_the_checkpoint_is_on_a_row(tmp_path):
    """On the save grid nothing is left between the last row and the checkpoint: the replay of the last saved
    interval (from the anchor) still meets the edited map."""
    out = tmp_path / "r"
    run = interrupt_at(out, two_point("compiled"), X0, 400, 1, 150)
    assert run["checkpoint"]["step"] == int(rl.load(out).n[-1])  # save_every 1: on a row
    write_run(out, _edit(copy.deepcopy(run), "eta by 1e-12"))
    with pytest.raises(jg.RecordingError, match="cannot resume"):
        rl.resume(out)
    write_run(out, run)  # the original record: resumes to the uninterrupted orbit
    rl.resume(out)
    assert np.array_equal(rl.load(out).X, two_point("compiled").iterate(X0, 400))


def test_a_chain_whose_sites_moved_by_1e_12_is_refused(tmp_path):
    model = jg.GaudinModel(1.0, ((-1.0, 1), (0.5, 1), (2.0, 1)))
    m = jg.ChainTwoPointBacklund(model, 5 + 0.1j, backend="numpy")
    Xc = np.array([0.1, 0.2, 1.0, 0.3, -0.2, 0.9, 0.1, 0.1, 1.1])
    out = tmp_path / "c"
    run = interrupt_at(out, m, Xc, 40, 3, 20)
    edited = copy.deepcopy(run)
    edited["map"]["sites"][1][0] *= 1 + 1e-12
    write_run(out, edited)
    with pytest.raises(jg.RecordingError, match="cannot resume"):
        rl.resume(out)
    write_run(out, run)
    rl.resume(out)
    d = rl.load(out)
    assert np.array_equal(d.X, m.iterate(Xc, 40)[d.n])


def test_an_ensemble_checkpoint_replays_and_resumes_bit_for_bit(tmp_path):
    from jetgaudin.ensemble import BatchBacklund, sample_on_leaf

    Xb = sample_on_leaf(3, [0.4, -0.3, 1.5], 6, seed=3)
    m = BatchBacklund(np.full(6, 1.0), np.full(6, 5 + 0.1j))
    out = tmp_path / "e"
    run = interrupt_at(out, m, Xb, 50, 4, 21, program="jetgaudin ensemble")
    rl.resume(out)
    d = rl.load(out)
    assert np.array_equal(d.X, m.iterate(Xb, 50)[d.n])  # rows (steps + 1, B, 9)
    # the same interruption with the slot's state moved by one ulp (its digest recomputed) is refused
    out2 = tmp_path / "e2"
    run = interrupt_at(out2, m, Xb, 50, 4, 21, program="jetgaudin ensemble")
    ck = run["checkpoint"]
    with np.load(out2 / ck["file"]) as d:
        arrays = {k: np.array(d[k]) for k in d.files}
    arrays["X"][2, 5] = np.nextafter(arrays["X"][2, 5], np.inf)
    import io

    buf = io.BytesIO()
    np.savez(buf, **arrays)
    (out2 / ck["file"]).write_bytes(buf.getvalue())
    ck["sha256"] = hashlib.sha256(buf.getvalue()).hexdigest()
    write_run(out2, run)
    with pytest.raises(jg.RecordingError, match="cannot resume"):
        rl.resume(out2)
