"""The drivers' threads (``backlund/kernels/_drivers.py``: ``in_threads``, ``_threads``): large batches of the N = 3
lanes and of the branch rule run in pieces on the calling thread and helper threads; the results do not depend on
the split, Numba's thread count is honoured, an interruption stops the helpers, a forked child gets threads of
its own."""

from __future__ import annotations

import os
import threading
import time

import numpy as np
import pytest

from jetgaudin.backlund import kernels as K
from jetgaudin.backlund.kernels import _drivers
from jetgaudin.ensemble import sample_on_leaf


def _batch(n, seed):
    X = sample_on_leaf(3, [0.5, 0.2, 1.0], n, seed=seed)
    b = np.full(n, 1.0)
    eta = np.where(np.arange(n) % 2 == 0, 5 + 0.1j, 0.6 - 0.2j)  # both directions of the division in every block
    nu = K.nu_default(X, b, eta)
    nu[[3, 40, 97]] *= 1 + 1e-3  # used as given by the first step (cont=False): these orbits fail
    return X, b, eta, nu


@pytest.mark.parametrize("threads", [2, 3, 5])
def test_lanes_split_across_threads_equal_one_call(monkeypatch, threads):
    # 130 orbits = 5 blocks of 32 lanes (the last one partly used), split in pieces on `threads` threads (forced,
    # so that a one-CPU machine runs the split too): every output equals the one-thread call bit for bit
    X, b, eta, nu = _batch(130, 7)
    monkeypatch.setattr(_drivers, "_threads", lambda n, per_thread: 1)
    one = K.run_batch(X, b, eta, nu, False, 40, 3)
    monkeypatch.setattr(_drivers, "_threads", lambda n, per_thread: threads)
    split = K.run_batch(X, b, eta, nu, False, 40, 3)
    assert set(np.flatnonzero(one[4])) == {3, 40, 97}
    for a, c in zip(one, split, strict=True):
        assert np.array_equal(a, c)


def test_thread_count_follows_numba_and_the_work():
    import numba

    per = _drivers.BRANCH_ORBITS_PER_THREAD
    saved = numba.get_num_threads()
    assert _drivers._threads(per - 1, per) == 1  # too little work for a second thread
    assert _drivers._threads(100 * per, per) == saved
    assert _drivers._threads(2 * per, per) == min(2, saved)
    try:
        numba.set_num_threads(1)
        assert _drivers._threads(100 * per, per) == 1
    finally:
        numba.set_num_threads(saved)


def test_pieces_cover_the_range_once():
    seen = []
    lock = threading.Lock()

    def part(i0, i1):
        with lock:
            seen.extend(range(i0, i1))

    for n, threads in ((1, 3), (5, 3), (100, 2), (1000, 4)):
        seen.clear()
        _drivers.in_threads(part, n, threads)
        assert sorted(seen) == list(range(n))


@pytest.mark.parametrize(("n", "threads", "least"),
                         [(625, 2, 5), (100000, 2, 8192), (7, 4, 1), (3, 2, 5), (1000, 16, 1)])
def test_guided_pieces_shrink_to_the_least_piece(n, threads, least):
    # each piece 1/(2 threads) of what is left, at least `least` (or what is left): the pieces cover [0, n) in
    # order, never grow, and the last ones are small, so that the threads finish within about a least piece of each
    # other; at least one piece per thread where n allows
    e = _drivers.guided_edges(n, threads, least)
    sizes = np.diff(e)
    assert e[0] == 0 and e[-1] == n and np.all(sizes > 0)
    assert np.all(np.diff(sizes) <= 0)
    lo = max(1, min(least, n // threads))
    assert np.all(sizes[:-1] >= lo)
    assert sizes[-1] <= max(lo, -(-n // (2 * threads)))
    assert len(sizes) >= min(n, threads)
    left = n - np.array(e[:-1])
    assert np.all(sizes == np.minimum(left, np.maximum(lo, -(-left // (2 * threads)))))


def test_an_interruption_stops_the_helpers():
    # the calling thread raises (as KeyboardInterrupt would) in its first piece: the helper finishes the piece it
    # holds and takes no other; the exception reaches the caller
    done = []
    main = threading.main_thread()

    def part(i0, i1):
        if threading.current_thread() is main:
            raise KeyboardInterrupt
        time.sleep(0.05)
        done.append(i0)

    with pytest.raises(KeyboardInterrupt):
        _drivers.in_threads(part, 64, 2)
    # of 13 guided pieces the helper takes 1 (at most a few if the calling thread is descheduled for a while);
    # without the stop it would take the other 12 (0.6 s)
    assert len(done) < 8


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork")
def test_a_forked_child_gets_threads_of_its_own():
    # the pool's threads do not exist in a forked child: the driver makes a new pool there (a stale one would hang)
    got = []
    _drivers.in_threads(lambda i0, i1: got.append(i1 - i0), 16, 2)  # the parent's pool exists
    pid = os.fork()
    if pid == 0:  # the child: exit code 0 when the split ran
        try:
            seen = []
            _drivers.in_threads(lambda i0, i1: seen.append((i0, i1)), 16, 2)
            os._exit(0 if sum(i1 - i0 for i0, i1 in seen) == 16 else 1)
        except BaseException:
            os._exit(2)
    deadline = time.monotonic() + 60
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        if time.monotonic() > deadline:
            os.kill(pid, 9)
            os.waitpid(pid, 0)
            pytest.fail("the forked child hung in in_threads")
        time.sleep(0.02)
    assert os.waitstatus_to_exitcode(status) == 0


def test_an_invalid_numba_setting_is_one_line_naming_it(tmp_path):
    # NUMBA_NUM_THREADS=0 makes Numba's import fail (ValueError); the kernels' set-up turns it into a
    # KernelSetupError: in the library a typed error, in the CLI one line and exit code 2 naming the setting, not
    # an option
    import subprocess
    import sys

    env = dict(os.environ, NUMBA_NUM_THREADS="0")
    lib = subprocess.run([sys.executable, "-c", (
        "import numpy as np, jetgaudin as jg\n"
        "try:\n"
        "    jg.TwoPointBacklund(1.0, 5 + 0.1j).iterate(np.ones(9), 3, kernel='compiled')\n"
        "except jg.KernelSetupError as e:\n"
        "    print('typed:', e)\n")], env=env, capture_output=True, text=True, timeout=120)
    assert lib.returncode == 0 and lib.stdout.startswith("typed: Numba cannot start")
    assert "NUMBA_NUM_THREADS" in lib.stdout
    cli = subprocess.run([sys.executable, "-m", "jetgaudin", "ensemble", "--orbits", "100", "--steps", "2", "--out",
                          str(tmp_path / "run")], env=env, capture_output=True, text=True, timeout=120)
    lines = cli.stderr.strip().splitlines()
    assert cli.returncode == 2 and len(lines) == 1, cli.stderr
    assert lines[0].startswith("jetgaudin ensemble: error: Numba cannot start") and "--eta" not in lines[0]
