"""Tests of tools/dev/count_flops.py, the instrumented FLOP count of the physics step
(docs/scaling.md): the classification of instructions by lanes, and the reading of a callgrind
dump (self cost only; other objects apart). The objdump side is replaced by a fixed table.

Run: python3 -m pytest tests/tools/test_count_flops.py   (ctest does this)
"""

from __future__ import annotations

import pytest
from tool_loader import load_tool

flops = load_tool("count_flops")


@pytest.mark.parametrize("mnemonic, operands, expected", [
    ("addsd", "%xmm1,%xmm0", ("add", 1)),
    ("subsd", "0x8(%rax),%xmm2", ("add", 1)),
    ("mulpd", "%xmm1,%xmm0", ("mul", 2)),
    ("vmulpd", "%ymm1,%ymm2,%ymm3", ("mul", 4)),
    ("vdivpd", "%zmm1,%zmm2,%zmm3", ("div", 8)),
    ("vsqrtsd", "%xmm1,%xmm1,%xmm1", ("sqrt", 1)),
    ("mulss", "%xmm1,%xmm0", ("mul", 1)),
    ("vaddps", "%ymm0,%ymm1,%ymm1", ("add", 8)),
    ("maxsd", "%xmm1,%xmm0", ("minmax", 1)),
    ("cvtsd2ss", "%xmm0,%xmm0", ("convert", 1)),
    ("vcvtpd2psy", "%ymm0,%xmm0", ("convert", 4)),
])
def test_arithmetic_counts_its_lanes(mnemonic, operands, expected):
    assert flops.classify(mnemonic, operands) == expected


@pytest.mark.parametrize("mnemonic", ["andpd", "vblendvpd", "vcmppd", "movsd", "vxorpd", "ucomisd",
                                      "addq", "vpaddq", "mulq", "vgatherdpd"])
def test_logic_moves_and_integer_arithmetic_are_not_flops(mnemonic):
    assert flops.classify(mnemonic, "%ymm1,%ymm2,%ymm3") is None


def test_a_dump_counts_self_cost_and_keeps_other_objects_apart():
    code = {0x100: ("vmulpd", "%ymm1,%ymm2,%ymm3"), 0x104: ("vaddsd", "%xmm1,%xmm2,%xmm3"),
            0x108: ("call", "200 <g>"), 0x10c: ("movq", "%rax,%rbx"), 0x200: ("divsd", "%xmm1,%xmm0")}
    dump = """ob=/bin/prog
fn=int softevo::physics::(anonymous namespace)::run_link_stretch<softevo::physics::(anonymous namespace)::LanesAvx2, 1>(int)
0x100 0 10
0x104 0 10
cob=/bin/prog
cfn=g(double)
calls=3 0x200
0x108 0 999
0x10c 0 5
fn=g(double)
0x200 0 3
ob=/lib/libm.so.6
fn=sin
0x300 0 7
""".splitlines()
    c = flops.count(dump, "/bin/prog", code)
    assert c.instructions == 10 + 10 + 5 + 3 + 7  # the 999 after calls= is g's inclusive cost
    assert c.outside == 7
    assert c.ops["mul"] == 40 and c.ops["add"] == 10 and c.ops["div"] == 3
    assert c.flops == 53
    assert c.flops_by_function == {"run_link_stretch": 50, "g": 3}
    assert c.instructions_by_function["run_link_stretch"] == 25


def test_a_binary_given_by_relative_path_matches_the_absolute_object_of_the_dump(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    dump = [f"ob={tmp_path}/bin/prog", "fn=f(double)", "0x100 0 4"]
    c = flops.count(dump, "bin/prog", {0x100: ("mulsd", "%xmm1,%xmm0")})
    assert c.outside == 0 and c.ops["mul"] == 4


@pytest.mark.parametrize("mnemonic, operands, expected", [
    ("vmulpd", "%ymm1,%ymm2,%ymm3", ("fp arithmetic", 0, 0)),
    ("vaddpd", "0x20(%rax),%ymm2,%ymm3", ("fp arithmetic", 1, 0)),  # the load is micro-fused
    ("vcvtpd2psy", "%ymm0,%xmm0", ("fp convert", 0, 0)),
    ("vcvtps2pd", "%xmm0,%ymm0", ("fp convert", 0, 0)),
    ("vunpcklpd", "%ymm1,%ymm0,%ymm2", ("fp shuffle", 0, 0)),
    ("vperm2f128", "$0x20,%ymm2,%ymm0,%ymm1", ("fp shuffle", 0, 0)),
    ("vbroadcastsd", "%xmm0,%ymm0", ("fp shuffle", 0, 0)),
    ("vbroadcastsd", "0x8(%rdi),%ymm0", ("load", 1, 0)),  # done by the load unit
    ("vblendpd", "$0xc,%ymm1,%ymm0,%ymm2", ("fp blend/logic/compare", 0, 0)),
    ("vxorpd", "%ymm1,%ymm0,%ymm2", ("fp blend/logic/compare", 0, 0)),
    ("vcmpltpd", "%ymm1,%ymm0,%ymm2", ("fp blend/logic/compare", 0, 0)),
    ("vmovmskpd", "%ymm0,%eax", ("fp blend/logic/compare", 0, 0)),
    ("vmovapd", "%ymm0,%ymm1", ("fp move", 0, 0)),
    ("vmovupd", "(%rax,%rdx,8),%ymm0", ("load", 1, 0)),
    ("vmovupd", "%ymm0,0x40(%rsp)", ("store", 0, 1)),
    ("vmaskmovpd", "%ymm0,%ymm1,(%rax)", ("store", 0, 1)),
    ("movslq", "0x4(%rax),%rdx", ("load", 1, 0)),
    ("mov", "%rax,0x8(%rsp)", ("store", 0, 1)),
    ("lea", "0x8(%rax,%rdx,8),%rcx", ("integer and branch", 0, 0)),  # an address, not a load
    ("add", "$0x4,%rax", ("integer and branch", 0, 0)),
    ("cmp", "%eax,0x10(%rsp)", ("integer and branch", 1, 0)),
    ("jne", "1234 <f+0x40>", ("integer and branch", 0, 0)),
])
def test_instructions_are_sorted_by_the_unit_that_executes_them(mnemonic, operands, expected):
    assert flops.instruction_class(mnemonic, operands) == expected


def test_classes_add_up_to_the_instructions_of_the_binary():
    code = {0x100: ("vmulpd", "(%rax),%ymm2,%ymm3"), 0x104: ("vunpcklpd", "%ymm1,%ymm0,%ymm2"),
            0x108: ("vmovupd", "%ymm0,(%rdx)"), 0x10c: ("add", "$0x1,%rax")}
    dump = ["ob=/bin/prog", "fn=f(double)", "0x100 0 4", "0x104 0 2", "0x108 0 3", "0x10c 0 5",
            "ob=/lib/libm.so.6", "fn=sin", "0x300 0 7"]
    c = flops.count(dump, "/bin/prog", code)
    assert c.classes == {"fp arithmetic": 4, "fp shuffle": 2, "store": 3, "integer and branch": 5}
    assert sum(c.classes.values()) == c.instructions - c.outside
    assert c.memory == {"loads": 4, "stores": 3}
