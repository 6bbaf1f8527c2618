"""Hostile xacro: a few kilobytes that expand to gigabytes or hours (a property doubled 39 times,
macros calling the next twice 28 levels deep, a YAML alias bomb through ``xacro.load_yaml``,
``${10**(10**8)}`` and its kin) are refused in one line naming the file and the bound, in
seconds and within a small memory cap; an include that is not XML is named. Each hostile file is
expanded in a child process capped at 2 GiB of address space and a wall-clock timeout, so a bound
that fails cannot take the machine down. Real expressions expand exactly as xacro expands them."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from hostile_util import assert_one_line_error, run_cli
from mobmanip.descriptions import xacro as guarded
from mobmanip.descriptions.xacro import expand_xacro

ROOT = Path(__file__).resolve().parents[1]
MEMORY_CAP = 2 << 30  # bytes of address space for each child
TIMEOUT = 30  # s: a child past it is a failure (the refusals come within a few seconds)

HEAD = '<?xml version="1.0"?>\n<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'
TAIL = '<link name="base_link"/>\n</robot>\n'


def _write(path: Path, body: str) -> Path:
    path.write_text(HEAD + body + TAIL)
    return path


def _doubled(tmp_path: Path) -> Path:
    props = ['<xacro:property name="p0" value="xxxxxxxx"/>']
    props += [f'<xacro:property name="p{k}" value="${{p{k - 1}}}${{p{k - 1}}}"/>' for k in range(1, 40)]
    return _write(tmp_path / "doubled.urdf.xacro", "\n".join(props) + '\n<link name="${p39}"/>\n')


def _macro_tree(tmp_path: Path, levels: int = 28) -> Path:
    macros = ['<xacro:macro name="m0" params=""><link name="leaf"/></xacro:macro>']
    macros += [f'<xacro:macro name="m{k}" params=""><xacro:m{k - 1}/><xacro:m{k - 1}/></xacro:macro>'
               for k in range(1, levels + 1)]  # fmt: skip
    return _write(tmp_path / "tree.urdf.xacro", "\n".join(macros) + f"\n<xacro:m{levels}/>\n")


def _yaml_bomb(tmp_path: Path) -> Path:
    lines = ['a: &a ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for previous, name in zip("abcdefgh", "bcdefghi"):
        lines.append(f"{name}: &{name} [" + ", ".join([f"*{previous}"] * 9) + "]")
    (tmp_path / "bomb.yaml").write_text("\n".join(lines) + "\n")
    body = '<xacro:property name="y" value="${xacro.load_yaml(\'bomb.yaml\')}"/>\n<link name="${y}"/>\n'
    return _write(tmp_path / "yaml.urdf.xacro", body)


def _expression(tmp_path: Path, expression: str) -> Path:
    return _write(tmp_path / "expression.urdf.xacro", f'<link name="l${{{expression}}}"/>\n')


def _in_a_child(argv, overrides: dict | None = None) -> tuple[int, str, float, float]:
    """``mobmanip ARGV`` in a child capped at :data:`MEMORY_CAP` and :data:`TIMEOUT`, with module
    constants of the xacro reader overridden; (exit code, stderr, CPU seconds, peak MiB). The
    child's CPU time, not the wall clock's: the bound is on the work, which a busy machine (a
    parallel test run) does not change."""
    setup = "".join(f"X.{name} = {value!r}\n" for name, value in (overrides or {}).items())
    code = (
        "import sys\n"
        "from mobmanip.descriptions import xacro as X\n"
        f"{setup}"
        "from mobmanip.cli import main\n"
        "try:\n"
        f"    code = main({[str(a) for a in argv]!r})\n"
        "except SystemExit as exc:\n"
        "    code = exc.code\n"
        # the child's own peak (VmHWM, kB): getrusage's ru_maxrss survives exec, so a child of a
        # test process grown to 1.6 GB reported 1.6 GB whatever it did itself
        "peak = [l for l in open('/proc/self/status') if l.startswith('VmHWM:')][0].split()[1]\n"
        "print(peak, file=sys.stdout)\n"
        "sys.exit(code)\n"
    )

    def cap():
        resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP, MEMORY_CAP))

    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=TIMEOUT,
                          preexec_fn=cap, env=env)  # fmt: skip
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    seconds = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    peak = int(done.stdout.strip().splitlines()[-1]) / 1024 if done.stdout.strip() else float("nan")
    return done.returncode, done.stderr, seconds, peak


def _refused(path: Path, *needles: str, overrides: dict | None = None, seconds: float = 10.0) -> str:
    code, err, took, peak = _in_a_child(["init-spec", path, "--list-frames"], overrides)
    line = assert_one_line_error(code, err, f"xacro {path}: refused: ", *needles)
    assert "memory" not in line.lower()
    assert took < seconds, (took, line)
    assert peak < 1024, (peak, line)  # MiB
    return line


def test_a_property_doubled_39_times_is_refused(tmp_path):
    _refused(_doubled(tmp_path), "evaluates to 33,554,432 characters", f"more than the {guarded.MAX_VALUE_CHARS:,}")


def test_macros_calling_the_next_twice_28_levels_deep_are_refused(tmp_path):
    _refused(_macro_tree(tmp_path), f"more than {guarded.MAX_MACRO_EXPANSIONS:,} macro calls")


def test_a_yaml_alias_bomb_is_refused(tmp_path):
    _refused(_yaml_bomb(tmp_path), "the YAML file bomb.yaml", f"more than {guarded.MAX_YAML_NODES:,} values")


@pytest.mark.parametrize(
    ("expression", "needle"),
    [
        ("10**(10**8)", "raises 10 to the power 100000000"),
        ("(10**100)**(10**6)", "raises an integer of 333 bits to the power 1000000"),
        ("1 &lt;&lt; 10**9", "shifts 1 left by 1000000000"),
        ("'x' * 10**10", "repeats a sequence of 1 items 10000000000 times"),
        ("len([0] * 10**9)", "repeats a sequence of 1 items 1000000000 times"),
        ("len(list(range(10**9)))", "range(1000000000) of 1,000,000,000 items"),
        ("len(list(python.range(10**9)))", "range(1000000000) of 1,000,000,000 items"),
        ("math.factorial(10**7)", "math.factorial(10000000)"),
        ("factorial(10**7)", "math.factorial(10000000)"),
        ("'x'.center(3000000000)", "calls center(3000000000)"),
        ("'%2000000000d' % 1", "width or precision of 2000000000"),
        ("(str(dict())[0] + ':>2000000000' + str(dict())[1]).format(1)", "width or precision of 2000000000"),
        ("[[0] * 2**20] * 2**20", "makes a value of more than 1,048,576 items"),
        ("str([[0] * 2**20] * 2**20)", "passes str() a value of more than 1,048,576 items"),
        ("len(python.sum([[0] * 2**20] * 2**20, []))", "passes sum() a value"),
        (
            "'x'.join(['y' * 2**20] * 2**20)",
            "passes join() a value of more than 1,048,576 items or 16,777,216 characters",
        ),
        ("('x' * 2**20).replace('x', 'y' * 2**20)", "calls replace() making 1,099,511,627,776 characters"),
        ("('\\t' * 2**20).expandtabs(2**20)", "calls expandtabs() making 1,099,512,676,352 characters"),
        (" + ".join(["('x' * 2**20)"] * 17), "joins texts into more than 16,777,216 characters"),
        (
            "math.prod(python.range(1, 10**5))",
            f"math.prod of integers of {sum(k.bit_length() for k in range(1, 10**5)):,} bits together",
        ),
    ],
)
def test_expressions_that_make_huge_values_are_refused(tmp_path, expression, needle):
    _refused(_expression(tmp_path, expression), needle, seconds=5.0)


def test_an_expression_that_loops_for_hours_meets_the_time_bound(tmp_path):
    path = _expression(tmp_path, "len([1 for i in range(10**6) for j in range(10**6)])")
    _refused(path, "expanding it takes more than 1 s", overrides={"MAX_SECONDS": 1.0}, seconds=6.0)


def test_an_expression_that_loops_long_meets_the_step_bound(tmp_path):
    path = _expression(tmp_path, "len([1 for i in range(1000) for j in range(1000)])")
    _refused(path, "its expressions take more than 100,000 steps", overrides={"MAX_STEPS": 100_000}, seconds=6.0)


def test_many_elements_meet_their_bound(tmp_path):
    """Macros within the call bound whose bodies add up past the element bound (lowered here)."""
    body = "".join(f'<link name="l{k}_${{n}}"/>' for k in range(50))
    macro = f'<xacro:macro name="many" params="n">{body}</xacro:macro>\n'
    calls = "".join(f'<xacro:many n="{k}"/>' for k in range(30))
    path = _write(tmp_path / "many.urdf.xacro", macro + calls + "\n")
    _refused(path, "more than 1,000 elements", overrides={"MAX_ELEMENTS": 1000})


def test_the_bound_names_the_included_file_where_it_is_met(tmp_path, capfd):
    # in this process: 10**(10**5) would take milliseconds even unguarded, never hang the run
    _expression(tmp_path, "10**(10**5)").rename(tmp_path / "part.xacro")
    top = _write(tmp_path / "top.urdf.xacro", '<xacro:include filename="part.xacro"/>\n')
    code, _, err = run_cli(capfd, "init-spec", top, "--list-frames")  # in this process: refused at once
    assert_one_line_error(code, err, f"xacro {top}: refused: ", "raises 10 to the power 100000,",
                          f"(in {tmp_path / 'part.xacro'}, which it includes)")  # fmt: skip


@pytest.mark.parametrize(
    ("name", "content"),
    [("part.txt", "this is not XML at all\n"), ("part.yaml", "a: [1, 2]\n"), ("part.xacro", "<robot><link></robot>")],
)
def test_an_include_that_is_not_xml_is_named(tmp_path, capfd, name, content):
    (tmp_path / name).write_text(content)
    top = _write(tmp_path / "top.urdf.xacro", f'<xacro:include filename="{name}"/>\n')
    code, _, err = run_cli(capfd, "init-spec", top, "--list-frames")
    assert_one_line_error(code, err, f"xacro {top}: ", f"the file {tmp_path / name} it includes is not XML")


def test_the_file_itself_not_xml_is_named_as_before(tmp_path, capfd):
    top = tmp_path / "top.urdf.xacro"
    top.write_text("not xml <<")
    code, _, err = run_cli(capfd, "init-spec", top, "--list-frames")
    line = assert_one_line_error(code, err, f"xacro {top}: xacro cannot expand it")
    assert "includes" not in line


#: Expressions a robot file may well hold: each must expand exactly as xacro expands it alone.
ORDINARY = """<xacro:property name="r" value="0.08"/>
<xacro:property name="n" value="${2**10}"/>
<xacro:property name="table" value="${xacro.load_yaml('table.yaml')}"/>
<xacro:macro name="wheel" params="side y">
  <link name="wheel_${side}"><visual><geometry><cylinder radius="${r}" length="${r/2}"/></geometry></visual></link>
</xacro:macro>
<xacro:wheel side="left" y="0.2"/><xacro:wheel side="right" y="-0.2"/>
<link name="a_${n}_${'%.3f' % pi}_${'-'.join([str(k * k) for k in range(5)])}_${math.factorial(6)}"/>
<link name="b_${python.sum(python.range(10))}_${'ab' * 3}_${[0] * 3}_${1 &lt;&lt; 8}_${round(2 ** 0.5, 6)}"/>
<link name="c_${table['joints'][1]['name']}_${len(table['shared'])}_${'x'.center(5)}_${max(3, 4)}"/>
<link name="d_${'%.2f' % r}_${7 if n > 3 else 0}_${int('12') * 2}_${math.comb(10, 3)}"/>
"""
TABLE = """defaults: &defaults {effort: 10, velocity: 2}
joints:
  - {name: shoulder, <<: *defaults}
  - {name: elbow, <<: *defaults}
shared: [*defaults, *defaults, *defaults]
"""


def test_ordinary_expressions_expand_as_xacro_expands_them(tmp_path):
    import xacro

    (tmp_path / "table.yaml").write_text(TABLE)
    path = _write(tmp_path / "ordinary.urdf.xacro", ORDINARY)
    text, _ = expand_xacro(path)
    reference = xacro.process_file(str(path.resolve()), verbosity=0).toxml()  # xacro alone, unguarded
    xacro.all_includes.clear()
    assert text == reference
    assert 'name="a_1024_3.142_0-1-4-9-16_720"' in text and 'name="c_elbow_3_  x  _4"' in text
    assert 'name="d_0.08_7_24_120"' in text and 'name="b_45_ababab_[0, 0, 0]_256_1.414214"' in text


def test_xacro_is_left_as_it_was_after_a_refusal(tmp_path, capfd):
    import math

    import xacro

    before = (xacro.eval_text, xacro.eval_all, xacro.safe_eval, xacro.parse, xacro.handle_macro_call)
    trace = sys.gettrace()
    code, _, err = run_cli(capfd, "init-spec", _expression(tmp_path, "10**(10**5)"), "--list-frames")
    assert code == 2 and "refused" in err
    assert (xacro.eval_text, xacro.eval_all, xacro.safe_eval, xacro.parse, xacro.handle_macro_call) == before
    symbols = xacro._global_symbols
    assert symbols["python"]["range"] is range and symbols["math"]["factorial"] is math.factorial
    assert sys.gettrace() is trace
    (tmp_path / "table.yaml").write_text(TABLE)
    text, _ = expand_xacro(_write(tmp_path / "ordinary.urdf.xacro", ORDINARY))
    assert 'name="a_1024_' in text


def test_an_include_cycle_is_named(tmp_path, capfd):
    include = '<xacro:include filename="{}"/>\n'
    a = _write(tmp_path / "a.urdf.xacro", include.format("b.xacro"))
    _write(tmp_path / "b.xacro", include.format("a.urdf.xacro"))
    code, _, err = run_cli(capfd, "init-spec", a, "--list-frames")
    assert_one_line_error(code, err, f"xacro {a}: refused: it includes {a} inside itself",
                          "(a.urdf.xacro -> b.xacro -> a.urdf.xacro)")  # fmt: skip
    itself = _write(tmp_path / "self.urdf.xacro", include.format("self.urdf.xacro"))
    code, _, err = run_cli(capfd, "init-spec", itself, "--list-frames")
    assert_one_line_error(code, err, "(self.urdf.xacro -> self.urdf.xacro)")


def test_a_file_included_twice_in_a_row_is_no_cycle(tmp_path):
    (tmp_path / "part.xacro").write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="p${1 + 1}"/></robot>'
    )
    top = _write(tmp_path / "top.urdf.xacro", '<xacro:include filename="part.xacro"/>' * 2 + "\n")
    text, _ = expand_xacro(top)
    assert text.count('<link name="p2"/>') == 2


def test_a_yaml_file_beyond_its_bound_is_refused_before_it_is_read(tmp_path):
    (tmp_path / "big.yaml").write_text("a: [" + ", ".join(["1"] * (guarded.MAX_YAML_BYTES // 3 + 1)) + "]\n")
    size = (tmp_path / "big.yaml").stat().st_size
    body = '<xacro:property name="y" value="${xacro.load_yaml(\'big.yaml\')}"/>\n<link name="l${len(y[\'a\'])}"/>\n'
    _refused(_write(tmp_path / "yaml.urdf.xacro", body), f"the YAML file big.yaml has {size:,} bytes",
             f"more than the {guarded.MAX_YAML_BYTES:,}", seconds=5.0)  # fmt: skip
