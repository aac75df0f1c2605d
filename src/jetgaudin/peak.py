r"""The FP64 peak of the device a run stepped on, and a run's rate as a fraction of it (issue 36).

``fraction = rate × flops_per_step / peak``: ``rate`` in orbit-steps per second, ``flops_per_step`` the hand count
of the route's step (:func:`jetgaudin.backlund.kernels.flops_per_step`: 345 for the real N = 3 form, the generic
route's count for other N; chains have no count, so no fraction), ``peak`` in FLOP/s:

* **CPU:** ``cores × clock × flops per cycle and core`` — the cores Numba runs on (its thread count, at most the
  CPUs this process may use), the clock the CPU reports (``cpuinfo_max_freq`` where the kernel exposes it, else
  ``/proc/cpuinfo``'s ``cpu MHz``: under a hypervisor often the nominal clock, below the boost clock the cores
  run at), and per cycle: 16 with FMA (two 4-wide FMA pipes: AVX2 hosts and AMD Zen 2–4, whose AVX-512 runs on
  the same 256-bit pipes), 32 for Intel AVX-512 (two 8-wide FMA units) and AMD family 26 (Zen 5), 8 with AVX and
  no FMA, 4 otherwise.  An estimate (the label says so): ``benchmarks/cpu_peak.py`` measures it.
* **GPU:** the FP64 rate without tensor cores from NVIDIA's data sheets (:data:`GPU_FP64_TFLOPS`), by the
  device's name; an unknown GPU has no peak (``None``), and no fraction is given.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

__all__ = ["Peak", "cpu_peak", "gpu_peak", "GPU_FP64_TFLOPS", "flops_per_step_of", "rate_text"]

#: FP64 TFLOP/s without tensor cores (NVIDIA data sheets), by a substring of the device name; the first match
#: wins, so the more specific names come first
GPU_FP64_TFLOPS: tuple[tuple[str, float], ...] = (
    ("GH200", 34.0),
    ("H200", 34.0),
    ("H100 PCIe", 25.6),
    ("H100 NVL", 30.0),
    ("H100", 34.0),
    ("A100", 9.7),
    ("A30", 5.2),
    ("V100", 7.8),
)


@dataclass(frozen=True)
class Peak:
    """A device's FP64 peak: ``device`` (in words), ``flops`` (FLOP/s, > 0) and ``basis`` (how it was obtained)."""

    device: str
    flops: float
    basis: str

    def __post_init__(self) -> None:
        if not (isinstance(self.flops, (int, float)) and math.isfinite(self.flops) and self.flops > 0):
            raise ValueError(f"Peak.flops must be a positive finite number of FLOP/s, got {self.flops!r}")


def _cpuinfo() -> dict[str, str]:
    info: dict[str, str] = {}
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if ":" in line:
                    k, v = line.split(":", 1)
                    info.setdefault(k.strip(), v.strip())
    except OSError:
        pass
    return info


def _clock_ghz(info: dict[str, str]) -> float | None:
    try:
        with open("/sys/devices/system/cpu/cpu0/cpufreq/cpuinfo_max_freq") as f:
            return int(f.read().strip()) / 1e6  # kHz
    except (OSError, ValueError):
        pass
    try:
        return float(info["cpu MHz"]) / 1e3
    except (KeyError, ValueError):
        return None


def flops_per_cycle(flags: set[str], vendor: str, family: int) -> int:
    """FP64 flops per cycle and core from the CPU's feature flags (module docstring)."""
    if "avx512f" in flags and ("Intel" in vendor or ("AMD" in vendor and family >= 26)):
        return 32
    if "fma" in flags:
        return 16
    return 8 if "avx" in flags else 4


def cpu_peak(cores: int | None = None) -> Peak | None:
    """The estimated FP64 peak of ``cores`` cores of this CPU (default: Numba's thread count, at most the CPUs
    this process may use); ``None`` where the clock cannot be read."""
    info = _cpuinfo()
    ghz = _clock_ghz(info)
    if not ghz or ghz <= 0:
        return None
    if cores is None:
        try:
            usable = len(os.sched_getaffinity(0))
        except (AttributeError, OSError):
            usable = os.cpu_count() or 1
        try:
            import numba

            cores = min(usable, numba.get_num_threads())
        except ImportError:
            cores = usable
    try:
        family = int(info.get("cpu family", "0"))
    except ValueError:
        family = 0
    per = flops_per_cycle(set(info.get("flags", "").split()), info.get("vendor_id", ""), family)
    name = info.get("model name", "CPU")
    return Peak(f"{name}, {cores} core(s)", cores * ghz * 1e9 * per,
                f"estimated: {cores} core(s) x {ghz:.2f} GHz (reported clock) x {per} flops/cycle")


def gpu_peak(name: str) -> Peak | None:
    """The FP64 peak of the GPU named ``name`` from :data:`GPU_FP64_TFLOPS`; ``None`` for a GPU not in it."""
    for key, tflops in GPU_FP64_TFLOPS:
        if key in name:
            return Peak(name, tflops * 1e12, f"{tflops:g} TFLOP/s FP64 without tensor cores (data sheet)")
    return None


def flops_per_step_of(N: int, chain: bool = False) -> int | None:
    """The flops of one step of the top's route for ``N`` (the real N = 3 form, the generic route otherwise);
    ``None`` for a chain (not counted)."""
    if chain:
        return None
    from .backlund.kernels import flops_per_step

    return flops_per_step(int(N))["total"]


def rate_text(rate: float, flops: int | None, peak: Peak | None) -> str:
    """``<rate> orbit-steps/s[ = <G> GFLOP/s at <f> flops/step, <p> % of <device>'s FP64 peak (<basis>)]``; the
    fraction only where both the flop count and the peak are known."""
    text = f"{rate:.3g} orbit-steps/s"
    if flops and peak is not None and math.isfinite(rate) and rate > 0:
        fl = rate * flops
        text += (f" = {fl / 1e9:.3g} GFLOP/s at {flops} flops/step, {100 * fl / peak.flops:.3g} % of the FP64 peak "
                 f"of {peak.device} ({peak.flops / 1e9:.4g} GFLOP/s, {peak.basis})")
    return text
