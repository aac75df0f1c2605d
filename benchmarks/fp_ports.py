"""Which x86 instructions take the FMA pipes' issue cycles on this CPU (issue 36: what bounds the N = 3 lanes).

    python benchmarks/fp_ports.py            # needs gcc (AVX-512 assembler) and an AVX-512 CPU

A loop of 16 independent 512-bit fused multiply-adds (16 accumulators: the FMA pipes' throughput bound, one
iteration = 16 cycles on AMD Zen 4) is timed alone and with K more instructions of one class per iteration,
independent of the FMAs and of each other.  An instruction class that issues on the FMA pipes adds ~1 cycle per
instruction (``vmulpd``, the control); one that runs elsewhere adds nothing until its own pipes are full
(``vaddpd``, the control).  Printed: ns per iteration (thread CPU time, best of 5 runs of 2·10⁷ iterations) and the
extra FMA-pipe cycles per added instruction, at the clock the FMA-only loop implies (16 cycles per iteration).

Written as C with inline assembly (the instruction, not what a compiler makes of a source): generated, compiled
with gcc into a temporary directory and run; nothing is kept.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

#: instruction classes: one AT&T template each ({d}: a destination zmm/k register, {off}: a byte offset in buf)
CLASSES = {
    "vmulpd (FMA pipes: control)": "vmulpd %%zmm20, %%zmm21, %%zmm{d}",
    "vaddpd (add pipes: control)": "vaddpd %%zmm20, %%zmm21, %%zmm{d}",
    "vcmppd zmm -> k": "vcmplepd %%zmm20, %%zmm21, %%k{k}",
    "vcmppd ymm -> k": "vcmplepd %%ymm20, %%ymm21, %%k{k}",
    "vcmppd zmm, mem -> k": "vcmpeqpd {off}(%0), %%zmm21, %%k{k}",
    "vpcmpq zmm -> k (integer)": "vpcmpgtq %%zmm20, %%zmm21, %%k{k}",
    "vptestmq zmm -> k": "vptestmq %%zmm20, %%zmm21, %%k{k}",
    "vpmovq2m zmm -> k (sign bits)": "vpmovq2m %%zmm20, %%k{k}",
    "vfpclasspd zmm -> k": "vfpclasspd $0x99, %%zmm20, %%k{k}",
    "vmaxpd": "vmaxpd %%zmm20, %%zmm21, %%zmm{d}",
    "vminpd": "vminpd %%zmm20, %%zmm21, %%zmm{d}",
    "vblendmpd {k}": "vblendmpd %%zmm20, %%zmm21, %%zmm{d} %{{%%k1%}}",
    "vmovapd reg {k}": "vmovapd %%zmm20, %%zmm{d} %{{%%k1%}}",
    "vmovapd reg {k}{z}": "vmovapd %%zmm20, %%zmm{d} %{{%%k1%}} %{{z%}}",
    "vxorpd": "vxorpd %%zmm20, %%zmm21, %%zmm{d}",
    "kandb": "kandb %%k1, %%k2, %%k{k}",
    "vpternlogq (bitwise select)": "vpternlogq $0xca, %%zmm20, %%zmm21, %%zmm{d}",
    "vpandq": "vpandq %%zmm20, %%zmm21, %%zmm{d}",
    "vpandnq": "vpandnq %%zmm20, %%zmm21, %%zmm{d}",
    "vpternlogq, mem operand": "vpternlogq $0xca, {off}(%0), %%zmm21, %%zmm{d}",
    "vpmovm2q k -> zmm": "vpmovm2q %%k1, %%zmm{d}",
    "load zmm": "vmovupd {off}(%0), %%zmm{d}",
    "store zmm": "vmovupd %%zmm{d}, {off}(%0)",
    "store zmm {k} (masked)": "vmovupd %%zmm{d}, {off}(%0) %{{%%k1%}}",
    "store ymm": "vmovupd %%ymm{d}, {off}(%0)",
    "vdivpd zmm": "vdivpd %%zmm20, %%zmm21, %%zmm{d}",
    "vsqrtpd zmm": "vsqrtpd %%zmm20, %%zmm{d}",
}


def source(n: int) -> tuple[str, list[tuple[str, int]]]:
    fma = [f"vfmadd231pd %%zmm16, %%zmm17, %%zmm{i}" for i in range(16)]
    lines = ["#include <stdio.h>", "#include <time.h>",
             "static double now(void){struct timespec t;clock_gettime(CLOCK_THREAD_CPUTIME_ID,&t);"
             "return t.tv_sec+1e-9*t.tv_nsec;}",
             "static double buf[2048] __attribute__((aligned(64)));"]
    runs = [("FMAs alone", 0)] + [(name, k) for name in CLASSES
                                  for k in ((1, 2) if name.startswith(("vdiv", "vsqrt")) else (4, 8))]
    for i, (name, k) in enumerate(runs):
        extra = [CLASSES[name].format(d=22 + j % 8, k=3 + j % 4, off=64 * (j % 16)) for j in range(k)] if k else []
        body = []
        for m, f in enumerate(fma):  # the extra instructions spread evenly among the FMAs
            body.append(f)
            if k and (m + 1) % (16 // k) == 0 and extra:
                body.append(extra.pop(0))
        asm = "\\n\\t".join(body + extra)
        lines.append(f'static void f{i}(long n){{for(long i=0;i<n;i++) __asm__ volatile("{asm}"::"r"(buf):"memory");}}')
    lines.append("int main(void){double best,t;")
    lines.append('__asm__ volatile("vbroadcastsd %0,%%zmm16\\n\\tvbroadcastsd %0,%%zmm17\\n\\tvbroadcastsd %0,'
                 '%%zmm20\\n\\tvbroadcastsd %0,%%zmm21\\n\\tkxnorb %%k0,%%k0,%%k1\\n\\tkxorb %%k0,%%k0,%%k2"'
                 '::"m"(buf[0]));')
    for i in range(16):
        lines.append(f'__asm__ volatile("vxorpd %%zmm{i},%%zmm{i},%%zmm{i}":::);')
    for i, (_name, k) in enumerate(runs):
        lines.append(f"best=1e9;for(int r=0;r<5;r++){{t=now();f{i}({n});t=now()-t;if(t<best)best=t;}}"
                     f'printf("%d %.4f\\n",{k},best/{n}*1e9);')
    lines.append("return 0;}")
    return "\n".join(lines), runs


def main() -> int:
    gcc = shutil.which("gcc")
    if gcc is None:
        print("fp_ports: gcc not found (it assembles the instruction loops)", file=sys.stderr)
        return 2
    src, runs = source(20_000_000)
    with tempfile.TemporaryDirectory() as d:
        c, exe = Path(d) / "ports.c", Path(d) / "ports"
        c.write_text(src)
        subprocess.run([gcc, "-O1", "-mavx512f", "-mavx512vl", "-mavx512dq", "-o", str(exe), str(c)], check=True)
        out = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout.split()
    ns = [float(x) for x in out[1::2]]
    cycle = ns[0] / 16  # the FMA-only loop: 16 cycles per iteration
    print(f"FMAs alone: {ns[0]:.3f} ns per 16 FMAs = {1 / cycle:.2f} GHz at one 512-bit FMA per cycle")
    print("| instruction | per 16 FMAs | ns/iteration | extra FMA-pipe cycles per instruction |")
    print("|---|---:|---:|---:|")
    for (name, k), t in zip(runs[1:], ns[1:], strict=True):
        print(f"| {name} | {k} | {t:.3f} | {(t - ns[0]) / cycle / k:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
