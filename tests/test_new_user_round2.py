"""What a new user met in the second round after issues 32 and 33, each fixed and held here:

* su(3) exact runs (``orbit --algebra su3 --dt``, ``flow --algebra su3 --method exact``) solved the per-orbit
  parameters of the exact step again at every saved chunk (a Newton solve each time): now once per run, and once
  more on a resume (bit for bit: the parameters are solved at the run's initial state, read back from run.json);
* ``flow --compare`` on a chain wrote none of the top's comparison figures: now the chain's y_0 figure with the
  map's points over the flow's lines, compare_drift.png (the chain's own integrals) and compare_distance.png;
* ``ensemble --algebra su3 --n`` ignored --n silently (as every chain, --input, --init-from and --resume did):
  refused in one line where nothing reads it;
* ``orbit --backend gpu`` was refused in a validation library's words ("Value error, 'gpu' is not one of ..."): one
  plain line naming the option, what the command takes and where the GPU is (``ensemble --backend gpu``); every other
  bad choice is worded the same way;
* ``--init``'s metavar and help said 3N on su(n) runs: the help gives the count of a top, an su(2) chain and su(3).
"""

from __future__ import annotations

import json
import os
import signal

import h5py
import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import run as rl
from jetgaudin.gaudin import sun_exact
from test_cli_chains import one_line_error
from test_run import run_cli

TRIG = jg.GaudinModel(0.5, [(0.0, 2), (1.0, 1)], family="trigonometric", gamma=0.7)
TRIG_ARGS = ["--sites", "0:2,1:1", "--family", "trigonometric", "--gamma", "0.7", "--b", "0.5"]
TRIG_X0 = np.array([0.3, 0.2, 0.9, 0.1, -0.2, 0.05, 0.5, 0.4, 0.6])

MODEL = jg.GaudinModel(0.5, [(0.0, 1), (1.0, 1)], algebra="su3")
X0 = np.round(np.random.default_rng(1).normal(size=16) * 0.5, 3)
INIT = ",".join(repr(float(v)) for v in X0)
W = np.round(np.random.default_rng(3).normal(size=MODEL.n_integrals), 3)  # as tests/test_cli_sun.py
WEIGHTS = ",".join(repr(float(v)) for v in W)
SU3 = ["--sites", "0:1,1:1", "--algebra", "su3", "--b", "0.5", "--init", INIT]


def _count_solves(monkeypatch) -> dict:
    """Counts the calls of ``exact_parameters`` (the Newton solve of one orbit's step parameters)."""
    calls = {"n": 0}
    solve = sun_exact.exact_parameters

    def counted(*a, **k):
        calls["n"] += 1
        return solve(*a, **k)

    monkeypatch.setattr(sun_exact, "exact_parameters", counted)
    return calls


# ---- 1. su(3) exact runs solve their parameters once per run ----------------------------------------------------

def test_orbit_dt_solves_once_per_run_and_once_per_resume(capsys, tmp_path, monkeypatch):
    """600 steps in chunks of 200 (save_every 100: the driver's fixed cuts of a non-invariant map) are 3 kernel
    calls and more reference steps; the parameters are solved once (the command's check at X0, kept for the run).
    Stopped by a SIGINT in its second call and resumed: one more solve (the replay's and the run's, shared), and
    the bytes of orbit.csv equal to one uninterrupted run's."""
    args = ("orbit", *SU3, "--hamiltonian", WEIGHTS, "--dt", "0.05", "--steps", "600", "--save-every", "100",
            "--no-plots", "--checkpoint-seconds", "0", "--backend", "compiled")
    calls = _count_solves(monkeypatch)
    code, _, err = run_cli(capsys, *args, "--out", tmp_path / "full")
    assert code == 0, err
    assert calls["n"] == 1
    advance, seen = sun_exact.SunExactFlow.advance, {"n": 0}

    def interrupted(self, *a, **k):
        seen["n"] += 1
        if seen["n"] == 2:
            os.kill(os.getpid(), signal.SIGINT)
        return advance(self, *a, **k)

    monkeypatch.setattr(sun_exact.SunExactFlow, "advance", interrupted)
    code, _, err = run_cli(capsys, *args, "--out", tmp_path / "cut")
    assert code != 0 and json.loads((tmp_path / "cut" / "run.json").read_text())["status"] == "interrupted"
    monkeypatch.setattr(sun_exact.SunExactFlow, "advance", advance)
    calls["n"] = 0
    code, _, err = run_cli(capsys, "orbit", "--resume", tmp_path / "cut")
    assert code == 0, err
    assert calls["n"] == 1
    assert (tmp_path / "cut" / "orbit.csv").read_bytes() == (tmp_path / "full" / "orbit.csv").read_bytes()


def test_flow_exact_solves_once(capsys, tmp_path, monkeypatch):
    """600 samples: 3 kernel calls (256, 256, 88), one solve."""
    calls = _count_solves(monkeypatch)
    code, _, err = run_cli(capsys, "flow", *SU3, "--method", "exact", "--hamiltonian", WEIGHTS, "--dt", "0.05",
                           "--steps", "600", "--no-plots", "--no-progress",
                           "--out", tmp_path / "f")
    assert code == 0, err
    assert calls["n"] == 1


def test_library_run_solves_once_and_is_the_one_call_orbit(tmp_path, monkeypatch):
    """A run of an unbound SunExactFlow (the library's own, not the command's) solves once, at X0, and its rows
    are those of one `advance` call with the parameters of X0 on the NumPy route cut in the same chunks: equal bit
    for bit to two calls of the bound map (200 + 200 steps)."""
    H = MODEL.hamiltonian(W)
    fm = sun_exact.SunExactFlow(H, 0.05, backend="numpy")
    calls = _count_solves(monkeypatch)
    spec = rl.RunSpec(fm, X0, 400, save_every=100, csv=False, checkpoint_seconds=0)
    rl.start(spec, tmp_path / "lib", handle_signals=False)
    assert calls["n"] == 1
    bound = fm.bind_run(X0)
    assert calls["n"] == 2 and bound.bind_run(X0) is bound  # bound once: binding again at X0 is the same map
    a = bound.advance(X0, None, 200, 100)
    b = bound.advance(a.X, None, 200, 100)
    assert np.array_equal(rl.load(tmp_path / "lib").X, np.concatenate([X0[None], a.rows, b.rows]))


# ---- 2. flow --compare on a chain draws the comparison -----------------------------------------------------------

def _capture(monkeypatch) -> dict:
    """Every figure the plotting package saves, by file name (checked, then saved as usual)."""
    import jetgaudin.plotting._chains as pch
    import jetgaudin.plotting._compare as pcmp
    from jetgaudin.plotting import _files

    seen, real = {}, _files.save_figure

    def spy(fig, path, dpi):
        seen[path.name] = fig
        return real(fig, path, dpi)

    for mod in (_files, pch, pcmp):
        monkeypatch.setattr(mod, "save_figure", spy)
    return seen


def test_flow_compare_on_a_jet_chain_draws_the_map_against_the_flow(capsys, tmp_path, monkeypatch):
    """A trigonometric chain with an order-2 site: the four figures are written and listed in run.json; each
    compare_drift panel holds the drift of that chain integral (model.integrals, not the top's), the flow's as a
    line and the map's as points, exactly the values of the stored orbits; chain_y0 draws the map's points over the
    flow's lines (the same rows); compare_distance is |X_map − X_flow| of the stored orbits."""
    seen = _capture(monkeypatch)
    init = ",".join(repr(float(v)) for v in TRIG_X0)
    out = tmp_path / "c"
    code, _, err = run_cli(capsys, "flow", *TRIG_ARGS, "--init", init, "--eta", "0.4+0.3i", "--compare", "--steps",
                           "12", "--no-progress", "--out", out)
    assert code == 0, err
    names = {"chain_y0.png", "chain_integrals.png", "compare_drift.png", "compare_distance.png"}
    run = json.loads((out / "run.json").read_text())
    assert names <= set(run["files"]) and names <= set(seen)
    assert all((out / n).stat().st_size > 10_000 for n in names)  # a drawn PNG, not an empty one
    flow = rl.load(out).X
    orbit = np.loadtxt(out / "orbit.csv", delimiter=",", skiprows=1)[:, 1:]
    assert orbit.shape == flow.shape
    fig = seen["compare_drift.png"]
    panels = [ax for ax in fig.axes if ax.get_visible()]
    labels = TRIG.integral_labels()
    assert [ax.get_title().split(" ")[0] for ax in panels] == labels  # 7 integrals: h1,1 ... J
    df = np.abs(TRIG.integrals(flow) - TRIG.integrals(flow[0]))
    dm = np.abs(TRIG.integrals(orbit) - TRIG.integrals(orbit[0]))
    for k, ax in enumerate(panels):
        fl, mp = ax.lines
        assert fl.get_linestyle() == "-" and mp.get_marker() == "."
        np.testing.assert_array_equal(fl.get_ydata(), df[df[:, k] > 0, k])
        np.testing.assert_array_equal(mp.get_ydata(), dm[dm[:, k] > 0, k])
    assert any("drift of the 7 integrals" in t.get_text() for t in fig.texts)
    dist = np.linalg.norm(orbit - flow, axis=-1)
    np.testing.assert_array_equal(seen["compare_distance.png"].axes[0].lines[0].get_ydata(), dist[dist > 0])
    # the flow is the map's interpolation: DOP853 at rtol 1e-12 over 12 time units (measured 9e-12; 1e-8 leaves room)
    assert dist.max() < 1e-8
    comp = seen["chain_y0.png"].axes[1]  # site 1's components: each a line (flow) then dots (map)
    y0_flow, y0_map = flow[:, :3], orbit[:, :3]
    for a in range(3):
        line, dots = comp.lines[2 * a], comp.lines[2 * a + 1]
        np.testing.assert_array_equal(line.get_ydata(), y0_flow[:, a])
        np.testing.assert_array_equal(dots.get_ydata(), y0_map[:, a])
        assert dots.get_linestyle() == "None"


# ---- 3. ensemble --n is honoured or refused -----------------------------------------------------------------------

@pytest.mark.parametrize("extra, words", [
    (["--sites", "0:1,1:1", "--algebra", "su3"], ["--n", "--sites", "drop --n"]),
    (["--sites", "0:2,1:1"], ["--n", "--sites"]),
    (["--resume", "RUN"], ["--n", "--resume", "drop --n"]),
    (["--input", "STATES"], ["--n", "--input", "drop --n"]),
    ([], ["--n", ">= 1"]),  # --n 0 below
])
def test_ensemble_n_is_refused_where_nothing_reads_it(capsys, tmp_path, extra, words):
    (tmp_path / "states.csv").write_text("1,0,0,0,1,0\n")
    extra = [str(tmp_path / "states.csv") if a == "STATES" else str(tmp_path / "run") if a == "RUN" else a
             for a in extra]
    out = tmp_path / "e"
    code, _, err = run_cli(capsys, "ensemble", *extra, "--n", "0" if not extra else "2", "--orbits", "2",
                           "--steps", "2", "--out", out)
    assert one_line_error(code, err, *words), err
    assert not out.exists()  # refused before anything is written


def test_ensemble_n_sets_the_sampled_order(capsys, tmp_path):
    code, _, err = run_cli(capsys, "ensemble", "--n", "2", "--casimirs", "1,2", "--orbits", "3", "--steps", "2",
                           "--no-progress", "--out", tmp_path / "e")
    assert code == 0, err
    with h5py.File(tmp_path / "e" / "ensemble.h5") as f:
        assert f["X0"].shape == (3, 6)  # N = 2: 3N = 6 components
        assert np.allclose(jg.integrals(np.array(f["X0"]), 1.0)[:, 2:], [1.0, 2.0], rtol=1e-12)  # on the leaf


# ---- 4. orbit/flow --backend gpu: one plain line naming where the GPU is ------------------------------------------

@pytest.mark.parametrize("command, given", [("orbit", ["--backend", "gpu"]), ("orbit", ["--kernel=gpu"]),
                                            ("flow", ["--backend", "gpu"])])
def test_backend_gpu_outside_ensemble_is_one_plain_line(capsys, tmp_path, command, given):
    code, _, err = run_cli(capsys, command, *given, "--steps", "2", "--out", tmp_path / "o")
    opt = given[0].split("=")[0]
    assert one_line_error(code, err, opt, f"{command} takes auto, compiled or numpy", "ensemble --backend gpu"), err
    assert "Value error" not in err and "Invalid value" not in err
    assert not (tmp_path / "o").exists()


def test_other_bad_choices_name_what_the_command_takes(capsys, tmp_path):
    code, _, err = run_cli(capsys, "flow", "--method", "dop853", "--out", tmp_path / "f")
    assert one_line_error(code, err, "--method", "DOP853, heyoka, exact or midpoint", "'dop853'"), err
    code, _, err = run_cli(capsys, "ensemble", "--backend", "cuda", "--out", tmp_path / "e")
    assert one_line_error(code, err, "--backend", "auto, compiled, numpy or gpu"), err
    assert "ensemble --backend gpu (" not in err  # ensemble has the GPU: no pointer to itself


# ---- 5. --init's help is right for a top and for both algebras ----------------------------------------------------

@pytest.mark.parametrize("command", ["orbit", "flow", "info"])
def test_init_help_gives_the_count_of_every_model(command):
    import typer

    from jetgaudin.cli._app import app

    opt = next(p for p in typer.main.get_command(app).commands[command].params if "--init" in p.opts)
    assert "3N" not in (opt.metavar or "")  # an su(3) state has 8M numbers, not 3N
    help_text = " ".join(opt.help.split())
    su2 = jg.GaudinModel(1.0, [(0.0, 2), (1.0, 1)])
    assert su2.n_state == 3 * su2.M and "with --sites 3M (M = N_1 + N_2 + ..." in help_text
    assert MODEL.n_state == 8 * MODEL.M and "--algebra su3 8M" in help_text
    assert "3N for a top of jet order N" in help_text


def test_su3_init_errors_do_not_ask_for_3n(capsys, tmp_path):
    code, _, err = run_cli(capsys, "orbit", *SU3[:-1], "1,2,x", "--eta", "0.4+0.1i", "--out", tmp_path / "o")
    assert one_line_error(code, err, "--init", "value 3"), err
    assert "3N" not in err


# ---- 2. su(3) exact runs written before (parameters solved at every chunk) still resume -------------------------

OLD_STEPS, OLD_EVERY = 800, 100  # kernel calls of 200 steps (the driver's fixed cuts of a non-invariant map)


def _su3_spec(old: bool) -> rl.RunSpec:
    """The su(3) exact run on the NumPy route; ``old``: as the code before ``bind_run`` ran it (parameters solved
    at the start of every kernel call), which writes no ``map_setup`` in run.json, as that code did not."""
    fm = sun_exact.SunExactFlow(MODEL.hamiltonian(W), 0.05, backend="numpy")
    return rl.RunSpec(fm, X0, OLD_STEPS, save_every=OLD_EVERY, checkpoint_seconds=0, _per_chunk_setup=old)


def _stop_at(step: int):
    """A progress callback sending SIGINT once the run has passed ``step`` (the driver stops after that call)."""
    def progress(n, steps):
        if n >= step:
            os.kill(os.getpid(), signal.SIGINT)
    return progress


def test_a_run_written_the_old_way_resumes_the_old_way_bit_for_bit(tmp_path, monkeypatch):
    """A directory written by the per-chunk code, stopped part-way, is resumed by the current code: the replay with
    the parameters of X0 does not meet its rows, the per-chunk replay does, and the run goes on that way to the end
    (recorded: run.json ``map_setup``, so a second resume goes straight to it): the orbit equals, bit for bit, the
    uninterrupted old-way run (which differs from the new way's, else this would prove nothing)."""
    rl.start(_su3_spec(True), tmp_path / "old", handle_signals=False)
    rl.start(_su3_spec(False), tmp_path / "new", handle_signals=False)
    old, new = rl.load(tmp_path / "old").X, rl.load(tmp_path / "new").X
    assert "map_setup" not in json.loads((tmp_path / "old" / "run.json").read_text())
    assert np.array_equal(old[:3], new[:3]) and not np.array_equal(old, new)  # the first call is the same

    cut = tmp_path / "cut"
    try:
        rl.start(_su3_spec(True), cut, progress=_stop_at(300))
    except rl.RunInterrupted:
        pass
    run = json.loads((cut / "run.json").read_text())
    assert run["status"] == "interrupted" and "map_setup" not in run
    assert run["checkpoint"]["step"] < OLD_STEPS and run["checkpoint"]["anchor"]["step"] > 0  # past the first call
    try:  # the first resume (the fallback) is itself stopped part-way
        rl.resume(cut, progress=_stop_at(run["checkpoint"]["step"] + 1))
    except rl.RunInterrupted:
        pass
    run2 = json.loads((cut / "run.json").read_text())
    assert run2["status"] == "interrupted" and run2["map_setup"] == "per_chunk"
    assert run["checkpoint"]["step"] < run2["checkpoint"]["step"] < OLD_STEPS

    def never(*a, **k):
        raise AssertionError("a run recorded as per_chunk was replayed with bound parameters")

    monkeypatch.setattr(sun_exact.SunExactFlow, "bind_run", never)
    res = rl.resume(cut, handle_signals=False)
    assert res.state is rl.RunStatus.COMPLETED
    assert np.array_equal(rl.load(cut).X, old)  # bit for bit the uninterrupted old-way run


def test_an_edited_old_way_run_is_still_refused(tmp_path):
    """Neither way reproduces a checkpoint state moved by one ulp: refused as before, nothing recorded."""
    from jetgaudin.run.files import write_run

    cut = tmp_path / "cut"
    try:
        rl.start(_su3_spec(True), cut, progress=_stop_at(300))
    except rl.RunInterrupted:
        pass
    run = json.loads((cut / "run.json").read_text())
    ck = run["checkpoint"]
    ck["X_hex"][4] = np.nextafter(float.fromhex(ck["X_hex"][4]), np.inf).hex()
    write_run(cut, run)  # a valid digest: what an editor produces
    with pytest.raises(jg.RecordingError, match="edited or corrupted"):
        rl.resume(cut, handle_signals=False)
    assert "map_setup" not in json.loads((cut / "run.json").read_text())


def test_the_command_resumes_an_old_way_run(capsys, tmp_path):
    """``orbit --resume`` on a directory written the old way: exit 0, the uninterrupted old-way orbit's rows."""
    rl.start(_su3_spec(True), tmp_path / "old", handle_signals=False)
    cut = tmp_path / "cut"
    try:
        rl.start(_su3_spec(True), cut, progress=_stop_at(300))
    except rl.RunInterrupted:
        pass
    code, _, err = run_cli(capsys, "orbit", "--resume", cut, "--no-plots", "--no-progress")
    assert code == 0, err
    assert np.array_equal(rl.load(cut).X, rl.load(tmp_path / "old").X)
    assert rl.read_run(cut)["map_setup"] == "per_chunk"
