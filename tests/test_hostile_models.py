"""Hostile inputs off the top's path (the reliability rules of docs/reliability.md), for an elliptic ONE-site model
(the Clebsch top, ``jg.clebsch_top(0.6)``: one elliptic jet site of order 2) and a trigonometric chain with a jet
site (orders 2 and 1), through the library and the command line:

(a) a second writer on a run directory is refused while the first holds its lock (a real run, stopped mid-run
    in a subprocess), and the first writer's data are durable: killed with SIGKILL, its directory resumes to the
    uninterrupted orbit bit for bit;
(b) a symlink planted in a run directory is not followed (start, resume, figures): its target keeps its bytes;
(c) a real file-size limit (``RLIMIT_FSIZE`` in a subprocess) mid-run gives one line on stderr, exit code 1, and a
    directory that resumes (the limit lifted) to the bytes of one uninterrupted run;
(d) each refusal leaves the run directory byte-identical (every file's bytes and mode, every mtime: the tree's
    snapshot before and after), as does writing into a non-empty foreign directory without --overwrite.

The top's and the rational chains' versions of these checks are in tests/test_run.py, tests/test_fs.py,
tests/test_reliability_refusals.py and tests/test_reliability_runlayer.py; this file extends them to the elliptic and
trigonometric families (their own map kinds, descriptions and compiled kernels)."""

from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import jetgaudin as jg
from jetgaudin import run as rl
from test_cli_chains import one_line_error
from test_data_safety import interrupt_at
from test_reliability_refusals import age, snapshot
from test_run import run_cli

SRC = str(Path(jg.__file__).resolve().parents[1])
ENV = dict(os.environ, PYTHONPATH=SRC)

# name: (model, state, eta, the command line's model options)
MODELS = {
    "clebsch": (jg.clebsch_top(0.6), np.array([0.72, 0.24, -0.54, 0.6, 0.0, 0.8]), 0.3 + 0.2j,
                ["--sites", "0:2", "--family", "elliptic", "--modulus", "0.6", "--b", "0"]),
    "trig-jet": (jg.GaudinModel(0.5, [(0.0, 2), (1.0, 1)], family="trigonometric", gamma=0.7),
                 np.array([0.3, 0.2, 0.9, 0.1, -0.2, 0.05, 0.5, 0.4, 0.6]), 0.4 + 0.3j,
                 ["--sites", "0:2,1:1", "--family", "trigonometric", "--gamma", "0.7", "--b", "0.5"]),
}
NAMES = list(MODELS)


def _map(name, backend="numpy"):
    model, _, eta, _ = MODELS[name]
    return jg.ChainTwoPointBacklund(model, eta, backend=backend)


def _cli(name, *extra):
    model, X0, eta, opts = MODELS[name]
    return ["orbit", *opts, "--init", ",".join(repr(float(v)) for v in X0), "--eta", f"{eta.real}+{eta.imag}i",
            "--no-progress", *extra]


def _unchanged(before, out) -> None:
    after = snapshot(out)
    changed = sorted(k for k in before.keys() | after.keys() if before.get(k) != after.get(k))
    assert not changed, f"a refusal changed {changed}"


def test_the_command_line_models_are_the_library_models(capsys, tmp_path):
    """The CLI options above build the library's map (its description in run.json) and its orbit, bit for bit."""
    for name in NAMES:
        code, _, err = run_cli(capsys, *_cli(name, "--steps", "4", "--backend", "numpy", "--no-plots",
                                             "--out", tmp_path / name))
        assert code == 0, err
        assert rl.read_run(tmp_path / name)["map"] == _map(name).describe()
        assert np.array_equal(rl.load(tmp_path / name).X, _map(name).iterate(MODELS[name][1], 4))


# ---- (a) one writer per run directory ------------------------------------------------------------------------------

_WRITER = """
import json, sys, time
import numpy as np, jetgaudin as jg
from jetgaudin import run as rl
m = jg.map_from_description(json.loads(sys.argv[2]))
X0 = np.array(json.loads(sys.argv[3]))

def progress(n, steps):
    if n >= 16:  # three chunks of 2 rows (4 steps) durable and checkpointed: stop in the fourth, holding the lock
        print("running", flush=True)
        time.sleep(300)

rl.start(rl.RunSpec(m, X0, 30, 2, checkpoint_seconds=0.0), sys.argv[1], progress=progress, max_chunk_steps=4,
         chunk_rows=2)
"""


@pytest.mark.parametrize("name", NAMES)
def test_a_second_writer_is_refused_while_the_first_runs(capsys, tmp_path, name):
    model, X0, _, _ = MODELS[name]
    out = tmp_path / "run"
    writer = subprocess.Popen([sys.executable, "-c", _WRITER, str(out), json.dumps(_map(name).describe()),
                               json.dumps(X0.tolist())], stdout=subprocess.PIPE, text=True, env=ENV)
    try:
        assert writer.stdout.readline().strip() == "running"
        age(out)
        before = snapshot(out)
        spec = rl.RunSpec(_map(name), X0, 30, 2)
        with pytest.raises(jg.RunLockedError, match=f"process {writer.pid}"):
            rl.start(spec, out, overwrite=True)
        with pytest.raises(jg.RunLockedError, match=f"process {writer.pid}"):
            rl.resume(out)
        _unchanged(before, out)
        code, _, err = run_cli(capsys, *_cli(name, "--steps", "30", "--out", out, "--overwrite"))
        assert one_line_error(code, err, str(writer.pid)), err
        code, _, err = run_cli(capsys, "orbit", "--resume", out)
        assert one_line_error(code, err, str(writer.pid)), err
        _unchanged(before, out)
    finally:
        writer.send_signal(signal.SIGKILL)  # the first writer dies mid-run: what it declared is durable
        writer.wait()
    assert rl.read_run(out)["last_safe_step"] == 12  # declared before the kill: durable
    rl.resume(out)
    assert np.array_equal(rl.load(out).X, _map(name).iterate(X0, 30)[::2])  # the NumPy route: any cut, same bits


# ---- (b) a symlink in a run directory is not followed --------------------------------------------------------------

@pytest.mark.parametrize("name", NAMES)
def test_planted_symlinks_are_not_followed_by_a_new_run(capsys, tmp_path, name):
    """Temporary names a run writes through (and replaces atomically): a symlink there is replaced, never written
    through, by the library and by the command line (figures included)."""
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    planted = ["orbit.csv.tmp", "orbit.h5.tmp", "run.json.tmp", ".jetgaudin-write-test", "chain_y0.png.tmp",
               "chain_integrals.png.tmp"]
    for where in ("lib", "cli"):
        out = tmp_path / where
        out.mkdir()
        for p in planted:
            (out / p).symlink_to(victim)
        if where == "lib":
            rl.start(rl.RunSpec(_map(name), MODELS[name][1], 6), out, overwrite=True)
        else:
            code, _, err = run_cli(capsys, *_cli(name, "--steps", "6", "--backend", "numpy", "--out", out,
                                                 "--overwrite"))
            assert code == 0, err
            assert (out / "chain_y0.png").stat().st_size > 0 and not (out / "chain_y0.png").is_symlink()
        assert victim.read_text() == "precious"
        assert not any(p.is_symlink() for p in out.iterdir())


def _interrupted(name, out, steps=12):
    """A run of ``steps`` steps stopped by a real SIGINT after step 4 (tests/test_data_safety.py): resumable."""
    interrupt_at(out, _map(name), MODELS[name][1], steps, 2, 4)
    assert 0 < rl.read_run(out)["last_safe_step"] < steps


@pytest.mark.parametrize("name", NAMES)
def test_planted_symlinks_are_not_followed_by_a_resume(capsys, tmp_path, name):
    """The same names planted in a resumable directory (no --overwrite clears them first): the library's and the
    command line's resume (figures drawn) write their files without writing through a link."""
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    for where in ("lib", "cli"):
        out = tmp_path / where
        _interrupted(name, out)
        for p in ("orbit.csv.tmp", "orbit.h5.tmp", "run.json.tmp", "chain_y0.png.tmp", "chain_integrals.png.tmp"):
            (out / p).symlink_to(victim)
        if where == "lib":
            assert rl.resume(out).status == "completed"
        else:
            code, _, err = run_cli(capsys, "orbit", "--resume", out, "--no-progress")
            assert code == 0, err
            assert not (out / "chain_y0.png").is_symlink() and (out / "chain_y0.png").stat().st_size > 0
        assert victim.read_text() == "precious"
        assert not any((out / f).is_symlink() for f in ("orbit.csv", "orbit.h5", "run.json"))
        assert np.array_equal(rl.load(out).X, _map(name).iterate(MODELS[name][1], 12)[::2])  # completed, same bits


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("file", ["orbit.csv", "orbit.h5", "run.json"])
def test_a_symlinked_run_file_is_refused_and_changes_nothing(capsys, tmp_path, name, file):
    """A run file replaced by a symlink to a copy outside: resume (library and command line) is refused in one line,
    the target is neither read as the run's nor written, and the directory is byte-identical."""
    out = tmp_path / "run"
    _interrupted(name, out)
    victim = tmp_path / "victim"
    os.replace(out / file, victim)
    (out / file).symlink_to(victim)
    kept = victim.read_bytes()
    age(out)
    before = snapshot(out)
    with pytest.raises(jg.JetGaudinError):
        rl.resume(out)
    _unchanged(before, out)
    code, _, err = run_cli(capsys, "orbit", "--resume", out)
    assert one_line_error(code, err), err
    _unchanged(before, out)
    assert victim.read_bytes() == kept


# ---- (c) a file-size limit mid-run ---------------------------------------------------------------------------------

def _limited(limit: int):
    def set_limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))
    return set_limit


#: 2 MB: orbit.h5 (48-72 bytes a row, the space of the whole run reserved up front: 0.96-1.44 MB) fits, and
#: orbit.csv (133-190 bytes a row) passes it after 10^4-1.5·10^4 of the 20000 rows
LIMIT = 2_000_000
STEPS = 20_000


@pytest.mark.parametrize("name", NAMES)
def test_the_command_line_under_a_file_size_limit_fails_in_one_line_and_resumes(capsys, tmp_path, name):
    """`orbit` (compiled route, 20000 steps) under `ulimit -f` 2 MB: one line on stderr naming the limit, exit code 1,
    status 'failed: file size limit reached'; `orbit --resume` without the limit completes to the bytes of one
    uninterrupted run (orbit.csv: the partial line cut at the limit is not kept)."""
    out = tmp_path / "limited"
    args = _cli(name, "--steps", str(STEPS), "--backend", "compiled", "--no-plots", "--checkpoint-seconds", "0")
    p = subprocess.run([sys.executable, "-m", "jetgaudin", *args, "--out", str(out)], capture_output=True, text=True,
                       timeout=300, env=ENV, preexec_fn=_limited(LIMIT))
    assert p.returncode == 1, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and "file size limit" in p.stderr and "Traceback" not in p.stderr
    run = rl.read_run(out)
    assert run["status"] == "failed: file size limit reached (ulimit -f)" and 0 < run["last_safe_step"] < STEPS
    p = subprocess.run([sys.executable, "-m", "jetgaudin", "orbit", "--resume", str(out), "--no-progress"],
                       capture_output=True, text=True, timeout=300, env=ENV)
    assert p.returncode == 0, p.stderr
    code, _, err = run_cli(capsys, *args, "--out", tmp_path / "whole")
    assert code == 0, err
    assert (out / "orbit.csv").read_bytes() == (tmp_path / "whole" / "orbit.csv").read_bytes()


_LIMITED_RUN = """
import json, sys
import numpy as np, jetgaudin as jg
from jetgaudin import run as rl
m = jg.map_from_description(json.loads(sys.argv[2]))
res = rl.start(rl.RunSpec(m, np.array(json.loads(sys.argv[3])), int(sys.argv[4]), checkpoint_seconds=0.0), sys.argv[1])
print(res.status)
"""


@pytest.mark.parametrize("name", NAMES)
def test_the_library_under_a_file_size_limit_reports_it_and_resumes(tmp_path, name):
    """`run.start` in a process under `ulimit -f`: a failed run (not an exception, not a death by SIGXFSZ), and
    `run.resume` without the limit ends on the compiled orbit of one call, bit for bit (the maps are chunk
    invariant)."""
    _, X0, _, _ = MODELS[name]
    out = tmp_path / "limited"
    p = subprocess.run([sys.executable, "-c", _LIMITED_RUN, str(out), json.dumps(_map(name, "compiled").describe()),
                        json.dumps(X0.tolist()), str(STEPS)], capture_output=True, text=True, timeout=300, env=ENV,
                       preexec_fn=_limited(LIMIT))
    assert p.returncode == 0, p.stderr[-800:]
    assert p.stdout.strip() == "failed: file size limit reached (ulimit -f)"
    assert 0 < rl.read_run(out)["last_safe_step"] < STEPS
    res = rl.resume(out)
    assert res.status == "completed"
    assert np.array_equal(rl.load(out).X, _map(name, "compiled").iterate(X0, STEPS))


# ---- (d) a foreign directory is not written into -------------------------------------------------------------------

@pytest.mark.parametrize("name", NAMES)
def test_a_non_empty_foreign_directory_is_refused_and_unchanged(capsys, tmp_path, name):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("not a run")
    (out / "sub").mkdir()
    age(out)
    before = snapshot(out)
    with pytest.raises(jg.RunDirectoryError, match="--overwrite|overwrite"):
        rl.start(rl.RunSpec(_map(name), MODELS[name][1], 5), out)
    _unchanged(before, out)
    code, _, err = run_cli(capsys, *_cli(name, "--steps", "5", "--out", out))
    assert one_line_error(code, err, "--overwrite"), err
    _unchanged(before, out)
