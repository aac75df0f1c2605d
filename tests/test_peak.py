"""The FP64 peak of the device and the rate line of `jetgaudin ensemble` (jetgaudin.peak; issue 36)."""

import re

import pytest

from jetgaudin import peak as pk
from jetgaudin.cli import main


def test_flops_per_cycle_rules():
    # two 4-wide FMA pipes (2 flops per FMA): 16; Zen 2-4's AVX-512 runs on the same pipes; Intel AVX-512 and Zen 5: 32
    assert pk.flops_per_cycle({"avx", "avx2", "fma"}, "AuthenticAMD", 25) == 16
    assert pk.flops_per_cycle({"avx", "avx2", "fma", "avx512f"}, "AuthenticAMD", 25) == 16
    assert pk.flops_per_cycle({"avx", "avx2", "fma", "avx512f"}, "AuthenticAMD", 26) == 32
    assert pk.flops_per_cycle({"avx", "avx2", "fma", "avx512f"}, "GenuineIntel", 6) == 32
    assert pk.flops_per_cycle({"avx"}, "GenuineIntel", 6) == 8
    assert pk.flops_per_cycle(set(), "GenuineIntel", 6) == 4


def test_gpu_peaks_from_the_table():
    # the more specific names win over "H100"; unknown GPUs have no peak
    assert pk.gpu_peak("NVIDIA H100 PCIe").flops == 25.6e12
    assert pk.gpu_peak("NVIDIA H100 80GB HBM3").flops == 34e12
    assert pk.gpu_peak("NVIDIA H200").flops == 34e12
    assert pk.gpu_peak("NVIDIA A100-SXM4-40GB").flops == 9.7e12
    assert pk.gpu_peak("NVIDIA GeForce RTX 4090") is None


def test_peak_refuses_a_nonpositive_rate():
    with pytest.raises(ValueError, match="positive"):
        pk.Peak("x", 0.0, "none")


def test_rate_text_fraction():
    peak = pk.Peak("test device", 100e9, "given")
    text = pk.rate_text(1e8, 349, peak)
    # 1e8 orbit-steps/s × 349 flops = 34.9 GFLOP/s = 34.9 % of 100 GFLOP/s (3 significant digits printed)
    assert text.startswith("1e+08 orbit-steps/s = 34.9 GFLOP/s at 349 flops/step, 34.9 % of the FP64 peak")
    assert pk.rate_text(1e8, None, peak) == "1e+08 orbit-steps/s"  # a chain: no flop count, no fraction
    assert pk.rate_text(1e8, 349, None) == "1e+08 orbit-steps/s"  # an unknown device: no fraction


def test_flops_per_step_of_the_routes():
    from jetgaudin.backlund.kernels import flops_per_step

    assert pk.flops_per_step_of(3) == flops_per_step(3, "n3")["total"]
    assert pk.flops_per_step_of(4) == flops_per_step(4)["total"]
    assert pk.flops_per_step_of(3, chain=True) is None


def test_cpu_peak_is_cores_times_clock_times_width():
    p = pk.cpu_peak(cores=2)
    if p is None:
        pytest.skip("no clock readable on this machine")
    m = re.search(r"2 core\(s\) x ([0-9.]+) GHz \(reported clock\) x (\d+) flops/cycle", p.basis)
    assert m, p.basis
    # the basis is printed to 2 decimals of GHz: the product agrees to 0.5 %
    assert p.flops == pytest.approx(2 * float(m.group(1)) * 1e9 * int(m.group(2)), rel=5e-3)


def test_ensemble_prints_the_rate_and_the_fraction_of_peak(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["ensemble", "--sample", "leaf", "--casimirs", "0.5,0.2,1", "--orbits", "40", "--steps", "20",
              "--out", str(tmp_path / "e"), "--no-progress"])
    assert exc.value.code in (0, None)
    out = capsys.readouterr().out
    lines = " ".join(out.split("\n")).split("rate: ")[1:]
    assert lines, out
    m = re.match(r"([0-9.e+]+) orbit-steps/s = ([0-9.e+]+) GFLOP/s at (\d+) flops/step, ([0-9.e+]+) % of the FP64",
                 lines[0])
    assert m, lines[0]
    rate, gflops, flops, pct = (float(g) for g in m.groups())
    assert flops == pk.flops_per_step_of(3)
    # the printed numbers are rounded to 3 significant digits: they agree to 1 %
    assert gflops == pytest.approx(rate * flops / 1e9, rel=1e-2)
    assert 0 < pct
