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

--classes also sorts every instruction by the unit that executes it: the vector/FP pipes
(arithmetic, conversions, shuffles and permutes, blends, logic and compares; register moves
are listed apart, as cores rename most of them away),
the load and store units (a memory operand of any instruction counts once), and the integer
side (index arithmetic, branches). On a core whose FP pipes are the bottleneck, the FP-pipe
instructions divided by the number of FP pipes is the fewest cycles this instruction stream
can take, whatever its FLOPs.
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


# Instruction classes of --classes (x86-64, AT&T syntax as objdump prints it).
CLASSES = ("fp arithmetic", "fp convert", "fp shuffle", "fp blend/logic/compare", "fp move",
           "load", "store", "integer and branch")
FP_PIPE_CLASSES = CLASSES[:4]  # register moves are renamed away (move elimination)
_SHUFFLE = re.compile(r"v?(unpck[lh]p[sd]|shufp[sd]|perm\w*|vperm2f128|vperm2i128|insertf\w*|"
                      r"extractf\w*|inserti\w*|extracti\w*|broadcast\w*|movddup|movs[lh]dup|"
                      r"movhlps|movlhps|pshuf\w*|palignr|punpck\w*|valign\w*|pbroadcast\w*|"
                      r"vpermi2\w*|vpermt2\w*|compress\w*|expand\w*)$")
_BLEND_LOGIC = re.compile(r"v?(blend\w*|pblend\w*|andn?p[sd]|orp[sd]|xorp[sd]|"
                          r"cmp\w*p[sd]|cmp\w*s[sd]|u?comis[sd]|movmskp[sd]|pand\w*|por\w*|"
                          r"pxor\w*|pcmp\w*|ptest|testp[sd]|kmov\w|kand\w*|kor\w*|kxor\w*|"
                          r"knot\w|kshift\w*|kortest\w|ktest\w|roundp[sd]|rounds[sd]|"
                          r"fixupimm\w*|ternlog\w*)$")
_VECTOR_MOVE = re.compile(r"v?(movap[sd]|movup[sd]|movs[sd]|movq|movd|movdq[au]\w*|maskmovp[sd]|"
                          r"vmaskmovp[sd]|movhp[sd]|movlp[sd]|vzeroupper)$")


def instruction_class(mnemonic: str, operands: str) -> tuple[str, int, int]:
    """(class, loads, stores) of one instruction for --classes: a memory operand is a load,
    or a store when it is the destination (AT&T: the last operand); a move between memory and
    a register is only that load or store."""
    ops = operands.split("<")[0]
    memory = "(" in ops and not mnemonic.startswith("lea") and not mnemonic.startswith("nop")
    reads_only = re.match(r"v?(cmp|test|u?comis|bt)", mnemonic) is not None  # no destination
    dest_is_memory = memory and ops.rstrip().endswith(")") and not reads_only
    loads = int(memory and not dest_is_memory)
    stores = int(dest_is_memory)
    is_vector = "%xmm" in ops or "%ymm" in ops or "%zmm" in ops or mnemonic.startswith("k")
    arithmetic = classify(mnemonic, operands)
    if arithmetic is not None:
        return ("fp convert" if arithmetic[0] == "convert" else "fp arithmetic"), loads, stores
    if re.match(r"v?cvt", mnemonic) and is_vector:
        return "fp convert", loads, stores
    if _VECTOR_MOVE.match(mnemonic) and is_vector:
        if memory:
            return ("store" if dest_is_memory else "load"), loads, stores
        return "fp move", 0, 0
    if _SHUFFLE.match(mnemonic):
        if memory and re.match(r"v?(p?broadcast|movddup)", mnemonic):
            return "load", 1, 0  # a broadcast from memory is done by the load unit
        return "fp shuffle", loads, stores
    if _BLEND_LOGIC.match(mnemonic) and is_vector:
        return "fp blend/logic/compare", loads, stores
    if is_vector and not memory:
        return "fp blend/logic/compare", 0, 0  # other vector integer operations
    if mnemonic.startswith("mov") and memory:
        return ("store" if dest_is_memory else "load"), loads, stores
    return "integer and branch", loads, stores


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
    classes: collections.Counter = field(default_factory=collections.Counter)  # --classes
    memory: collections.Counter = field(default_factory=collections.Counter)  # loads, stores

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
        cls, loads, stores = instruction_class(*instruction)
        result.classes[cls] += n
        result.memory["loads"] += n * loads
        result.memory["stores"] += n * stores
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
    p.add_argument("--classes", action="store_true",
                   help="also sort the instructions by the unit that executes them")
    p.add_argument("--fp-pipes", type=int, default=4,
                   help="FP/vector pipes of the core, for the cycle floor of --classes (default 4: "
                        "Zen 3/4/5, most Intel cores have 3)")
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
    if a.classes:
        inside = c.instructions - c.outside
        print("class\tinstructions per voxel-step\tshare")
        for cls in CLASSES:
            print(f"{cls}\t{c.classes[cls] / per:.1f}\t{c.classes[cls] / max(inside, 1):.1%}")
        print(f"memory operands per voxel-step: loads {c.memory['loads'] / per:.1f}, "
              f"stores {c.memory['stores'] / per:.1f}")
        fp = sum(c.classes[k] for k in FP_PIPE_CLASSES)
        print(f"FP-pipe instructions per voxel-step: {fp / per:.1f}, of them arithmetic and "
              f"conversions {(c.classes['fp arithmetic'] + c.classes['fp convert']) / max(fp, 1):.1%}; "
              f"at {a.fp_pipes} FP pipes at least {fp / per / a.fp_pipes:.1f} cycles per voxel-step")
    return 0


if __name__ == "__main__":
    sys.exit(main())
