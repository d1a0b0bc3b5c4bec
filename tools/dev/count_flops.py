#!/usr/bin/python3
"""Floating-point operations executed inside physics::step, counted by instrumentation
(docs/scaling.md, "How close the physics step is to the core").

valgrind's callgrind records how often every instruction ran (--dump-instr=yes); objdump names
each instruction. An arithmetic instruction counts once per lane it computes (addsd 1, addpd on
xmm 2, vaddpd on ymm 4, on zmm 8): add and subtract, multiply, divide and square root are the
FLOPs; min/max and float<->double conversions are listed beside them, blends, masks, compares
and logic are not counted. The step passes are built with -mno-fma and -ffp-contract=off
(physics/CMakeLists.txt, docs/model.md §0), so no instruction does two operations.

  valgrind --tool=callgrind --dump-instr=yes --compress-pos=no --compress-strings=no \\
      --collect-atstart=no '--toggle-collect=softevo::physics::step(*' \\
      '--dump-before=softevo::physics::build_model*' --callgrind-out-file=cg.out \\
      build/bin/softevo bench physics --scene block10x10x10 --steps 200 --runs 1 --simd avx2
  tools/dev/count_flops.py cg.out.2 build/bin/softevo --voxel-steps 200000     # pneuvox
  tools/dev/count_flops.py cg.out build/bin/softevo --voxel-steps 200000       # symplectic

(--dump-before splits the profile at each model the bench builds: part 2 holds the pneuvox
steps, the final file the symplectic ones.) Instructions of other objects (libm, libc) are
counted as instructions, not classified; `outside` reports them.
"""

from __future__ import annotations

import argparse
import collections
import os
import re
import subprocess
import sys
from dataclasses import dataclass, field

FLOP_KINDS = ("add", "mul", "div", "sqrt")
_ARITH = re.compile(r"v?(add|sub|mul|div|sqrt|min|max)(sd|ss|pd|ps)$")
_CONVERT = re.compile(r"v?cvt(sd2ss|ss2sd|pd2ps|ps2pd)[xy]?$")


def classify(mnemonic: str, operands: str) -> tuple[str, int] | None:
    """(kind, lanes) of a floating-point arithmetic instruction in objdump's AT&T syntax;
    None for everything else."""
    m = _ARITH.match(mnemonic)
    if m:
        op, kind = m.groups()
        width = 512 if "%zmm" in operands else 256 if "%ymm" in operands else 128
        lanes = 1 if kind in ("sd", "ss") else width // (64 if kind == "pd" else 32)
        return ({"add": "add", "sub": "add", "mul": "mul", "div": "div", "sqrt": "sqrt"}.get(op, "minmax"),
                lanes)
    m = _CONVERT.match(mnemonic)
    if m:
        if m.group(1) in ("sd2ss", "ss2sd"):
            return ("convert", 1)
        return ("convert", 4 if "%ymm" in operands else 2)
    return None


def disassemble(binary: str) -> dict[int, tuple[str, str]]:
    """Address -> (mnemonic, operands) of every instruction of `binary`."""
    text = subprocess.run(["objdump", "-d", "--no-show-raw-insn", binary], check=True,
                          capture_output=True, text=True).stdout
    code = {}
    for line in text.splitlines():
        m = re.match(r"\s*([0-9a-f]+):\s+(\S+)\s*(.*)", line)
        if m:
            code[int(m.group(1), 16)] = (m.group(2), m.group(3))
    return code


def function_name(fn: str) -> str:
    """The kernel's short name: run_link_stretch<LanesAvx2, Axis 1, ...> -> run_link_stretch."""
    m = re.search(r"(\w+)<softevo::physics::\(anonymous namespace\)::Lanes", fn) or re.search(r"(\w+)\(", fn)
    return m.group(1) if m else fn[:60]


@dataclass
class Count:
    instructions: int = 0
    outside: int = 0  # instructions of other objects (shared libraries)
    ops: collections.Counter = field(default_factory=collections.Counter)  # kind -> lane operations
    flops_by_function: collections.Counter = field(default_factory=collections.Counter)
    instructions_by_function: collections.Counter = field(default_factory=collections.Counter)

    @property
    def flops(self) -> int:
        return sum(self.ops[k] for k in FLOP_KINDS)


def count(dump_lines, binary: str, code: dict[int, tuple[str, str]]) -> Count:
    """Self cost of every instruction of a callgrind dump (the line after `calls=` is the
    callee's inclusive cost, already counted inside the callee, so it is skipped)."""
    result = Count()
    target = os.path.realpath(binary)  # callgrind names objects by absolute path
    obj = fn = ""
    after_call = False
    for line in dump_lines:
        if line.startswith("ob="):
            obj = os.path.realpath(line[3:].strip())
            continue
        if line.startswith("fn="):
            fn = function_name(line[3:].strip())
            continue
        if line.startswith("calls="):
            after_call = True
            continue
        m = re.match(r"(0x[0-9a-f]+)(?: \S+)? (\d+)$", line.strip())
        if not m:
            continue
        if after_call:
            after_call = False
            continue
        address, n = int(m.group(1), 16), int(m.group(2))
        result.instructions += n
        instruction = code.get(address) if obj == target else None
        if instruction is None:
            result.outside += n
            continue
        result.instructions_by_function[fn] += n
        kind = classify(*instruction)
        if kind:
            result.ops[kind[0]] += n * kind[1]
            if kind[0] in FLOP_KINDS:
                result.flops_by_function[fn] += n * kind[1]
    return result


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("dump", help="callgrind output file (--dump-instr=yes --compress-pos=no --compress-strings=no)")
    p.add_argument("binary", help="the profiled binary (objdump names its instructions)")
    p.add_argument("--voxel-steps", type=float, required=True, help="voxels x steps of the profile")
    p.add_argument("--functions", type=int, default=8, help="kernels to list")
    a = p.parse_args()
    with open(a.dump) as f:
        c = count(f, a.binary, disassemble(a.binary))
    per = a.voxel_steps
    print(f"instructions per voxel-step: {c.instructions / per:.1f} (in other objects: {c.outside / per:.1f})")
    print(f"FLOPs per voxel-step: {c.flops / per:.1f} = " +
          " + ".join(f"{k} {c.ops[k] / per:.1f}" for k in FLOP_KINDS) +
          f"; beside them min/max {c.ops['minmax'] / per:.1f}, conversions {c.ops['convert'] / per:.1f}")
    print("kernel\tFLOPs per voxel-step\tinstructions per voxel-step")
    for name, n in c.flops_by_function.most_common(a.functions):
        print(f"{name}\t{n / per:.1f}\t{c.instructions_by_function[name] / per:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
