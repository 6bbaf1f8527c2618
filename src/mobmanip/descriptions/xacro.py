"""xacro: a ROS robot description with macros, expanded to URDF without ROS.

:func:`read_xacro` (registered as the ``xacro`` format, suffixes ``.xacro`` and ``.urdf.xacro``)
expands the file with the ``xacro`` package from PyPI (no ROS install needed) and reads the URDF
it gives like any other (:func:`mobmanip.descriptions.urdf.urdf_description`): the description
keeps the ``.xacro`` file as its source.

- ``$(arg NAME)``: the values given as ``xacro_args`` (``--xacro-arg NAME=VALUE``, a spec's
  ``[xacro_args]`` table); an argument the file declares with ``<xacro:arg default=...>`` needs
  none. One that is used but has no value is an error naming it and the option that gives it.
- ``$(find PKG)`` (and ``find('PKG')`` in expressions): the package's folder, looked up in
  ``package_paths`` (``--package-path DIR``, a spec's ``package_paths``), then in the
  ``ROS_PACKAGE_PATH`` folders, then under ``share/`` of the ``AMENT_PREFIX_PATH`` prefixes. A
  folder in those lists may be the package itself (named like it, or with a ``package.xml``
  that names it) or hold it, up to :data:`SEARCH_DEPTH` levels down (a workspace's ``src/``).
  A package found nowhere is one error naming it and every folder searched.
- ``package://PKG/...`` mesh URIs of the expanded URDF resolve in the same folders.

xacro keeps its state in module globals, so expansions are serialised (a lock); what it prints
is captured and folded into the error message when the expansion fails.

What a file expands to is bounded, not only the bytes it reads (:data:`MAX_MACRO_EXPANSIONS`,
:data:`MAX_ELEMENTS`, :data:`MAX_VALUE_CHARS` and :data:`MAX_EXPANDED_CHARS` for the texts,
:data:`MAX_INT_BITS`, :data:`MAX_ITEMS`, :data:`MAX_TERMS` and :data:`MAX_STEPS` for what an
expression makes and does, :data:`MAX_YAML_BYTES` and :data:`MAX_YAML_NODES` for
``xacro.load_yaml``, :data:`MAX_SECONDS` for the whole): xacro's own functions are wrapped while
it runs, an expression's ``**``, ``<<``, ``*``, ``%``, ``+`` and calls go through a check of the
sizes they would make, and its loops are counted. A file past a bound, an include cycle or an
included file that is not XML is one :class:`~mobmanip.errors.XacroError` naming the file (and
the included one where it was met).
"""

from __future__ import annotations

import ast
import contextlib
import errno
import io
import math
import os
import re
import sys
import threading
import time
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any
from xml.etree import ElementTree
from xml.parsers.expat import ExpatError

from ..errors import XacroError
from ..support.reading import MAX_ROBOT_FILE_BYTES, file_refusal
from .description import RobotDescription
from .formats import DescriptionFormat, register_format
from .urdf import urdf_description

#: How deep below a package path a ``package.xml`` is looked for (a workspace: ``ws/src/repo/pkg``).
SEARCH_DEPTH = 4

_LOCK = threading.Lock()

#: Bounds on what a xacro file expands to (the bytes it reads are bounded apart, by
#: :data:`~mobmanip.support.reading.MAX_ROBOT_FILE_BYTES`): a few kilobytes can otherwise ask for
#: gigabytes (a property doubled forty times, macros calling the next twice) or hours (an
#: integer of a hundred million digits). A real robot stays far below each: TIAGo++'s files
#: expand some hundreds of macros into a few thousand elements in about a second.
MAX_MACRO_EXPANSIONS = 20_000
#: Elements xacro evaluates (each macro body and inserted block counts again).
MAX_ELEMENTS = 100_000
#: Characters of one evaluated text (an attribute, a property, a text node).
MAX_VALUE_CHARS = 1 << 24
#: Characters of all evaluated texts together.
MAX_EXPANDED_CHARS = 1 << 28
#: Bits of an integer an expression may make (about 19,700 decimal digits).
MAX_INT_BITS = 1 << 16
#: Items of a sequence an expression may make (``range``, ``[0] * n``, ``"x" * n``), and the
#: largest whole-number argument of a text's method or width of a format (a count, a width).
MAX_ITEMS = 1 << 20
#: Terms of ``math.factorial``, ``comb`` and ``perm`` (10,000! has about 118,000 bits).
MAX_TERMS = 10_000
#: Steps of expressions (calls and loop iterations) in one expansion.
MAX_STEPS = 10_000_000
#: Nodes of a YAML file ``xacro.load_yaml`` reads, its aliases expanded, and its bytes (the
#: pure-Python YAML reader takes about a second a megabyte).
MAX_YAML_NODES = 1_000_000
MAX_YAML_BYTES = 8 << 20
#: Seconds an expansion may take.
MAX_SECONDS = 60.0

#: The guard's name inside expressions (names with two leading underscores are refused in a
#: file's expressions, so a file cannot reach or replace it).
_GUARD = "__mobmanip_guard"
_CALL = "__mobmanip_call"


class _Refused(BaseException):
    """Raised through xacro (which wraps every Exception) when an expansion exceeds a bound."""


class _Guard:
    """The bounds of one expansion, put around xacro's own functions while it runs: the number
    of macro expansions and elements, the size of evaluated texts, the size of integers and
    sequences an expression makes, the nodes of loaded YAML, and the time (checked between
    xacro's steps and on every loop iteration of an expression)."""

    def __init__(self, module, top: Path) -> None:
        self.module = module
        self.top = top
        self.started = time.monotonic()
        self.deadline = self.started + MAX_SECONDS
        self.counts = {"macros": 0, "elements": 0, "chars": 0}  # made by the expansion so far
        self.steps = 0
        self.refused: str | None = None
        self._saved: list[tuple[Any, str, Any]] = []

    # -- refusing -------------------------------------------------------------------------
    def refuse(self, reason: str) -> None:
        stack = getattr(self.module, "filestack", None) or []
        current = next((f for f in reversed(stack) if f), None)
        where = f" (in {current}, which it includes)" if current is not None and Path(current) != self.top else ""
        self.refused = f"refused: {reason}{where}"
        raise _Refused(self.refused)

    def tick(self) -> None:
        if self.refused is not None:
            raise _Refused(self.refused)
        if time.monotonic() > self.deadline:
            self.refuse(f"expanding it takes more than {MAX_SECONDS:g} s")

    # -- installing -----------------------------------------------------------------------
    def _replace(self, owner, name: str, value) -> None:
        self._saved.append((owner, name, owner[name] if isinstance(owner, dict) else getattr(owner, name)))
        if isinstance(owner, dict):
            dict.__setitem__(owner, name, value)
        else:
            setattr(owner, name, value)

    def install(self) -> None:
        module = self.module
        for name in ("eval_all", "handle_macro_call", "eval_text", "safe_eval", "parse"):
            self._replace(module, name, getattr(self, f"_{name}")(getattr(module, name)))
        symbols = module._global_symbols
        guarded = {
            "range": self._range,  # also xacro's deprecated direct range(), a wrapper of the built-in
            "factorial": self._count_argument(math.factorial, "math.factorial"),
            "comb": self._count_argument(math.comb, "math.comb"),
            "perm": self._count_argument(math.perm, "math.perm"),
            "prod": self._product(math.prod, "math.prod"),
            "lcm": self._product(math.lcm, "math.lcm"),
        }
        originals = {"range": range, "factorial": math.factorial, "comb": math.comb, "perm": math.perm,
                     "prod": math.prod, "lcm": math.lcm}  # fmt: skip
        tables = [symbols] + [v for v in symbols.values() if isinstance(v, dict)]
        for table in tables:
            for key, value in list(dict.items(table)):
                if key == "load_yaml":
                    self._replace(table, key, self._load_yaml(value))
                elif key in guarded and (value is originals[key] or getattr(value, "__closure__", None)):
                    self._replace(table, key, guarded[key])

    def restore(self) -> None:
        for owner, name, value in reversed(self._saved):
            if isinstance(owner, dict):
                dict.__setitem__(owner, name, value)
            else:
                setattr(owner, name, value)
        self._saved.clear()

    def exceeds(self, what: str, amount: int, limit: int) -> bool:
        """Count ``amount`` more ``what`` (a key of :attr:`counts`); whether there are now more
        than ``limit``."""
        self.counts[what] += amount
        return self.counts[what] > limit

    # -- xacro's steps ---------------------------------------------------------------------
    def _eval_all(self, original):
        def eval_all(node, macros, symbols):
            self.tick()
            if self.exceeds("elements", 1, MAX_ELEMENTS):
                self.refuse(f"it expands to more than {MAX_ELEMENTS:,} elements")
            return original(node, macros, symbols)

        return eval_all

    def _handle_macro_call(self, original):
        def handle_macro_call(node, macros, symbols):
            if node.tagName.startswith("xacro:") and node.tagName != "xacro:call":
                if self.exceeds("macros", 1, MAX_MACRO_EXPANSIONS):
                    self.refuse(f"it expands more than {MAX_MACRO_EXPANSIONS:,} macro calls (at {node.tagName})")
            return original(node, macros, symbols)

        return handle_macro_call

    def _eval_text(self, original):
        def eval_text(text, symbols):
            self.tick()
            value = original(text, symbols)
            if not isinstance(value, (str, int, float, bool)) and _too_big(value):
                shown = " ".join(str(text).split())[:60]
                self.refuse(f"{shown!r} evaluates to more than {MAX_ITEMS:,} items or {MAX_VALUE_CHARS:,} characters")
            if isinstance(value, str):
                if len(value) > MAX_VALUE_CHARS:
                    shown = " ".join(str(text).split())[:60]
                    self.refuse(f"{shown!r} evaluates to {len(value):,} characters, more than the {MAX_VALUE_CHARS:,} "
                                "one value may take")  # fmt: skip
                if self.exceeds("chars", len(value), MAX_EXPANDED_CHARS):
                    self.refuse(f"its evaluated texts come to more than {MAX_EXPANDED_CHARS:,} characters")
            return value

        return eval_text

    def _parse(self, original):
        def parse(inp, filename=None):
            chain = [str(f) for f in (getattr(self.module, "filestack", None) or ()) if f]
            if filename is not None and inp is None and str(filename) in chain[:-1]:
                cycle = " -> ".join(Path(f).name for f in chain[chain.index(str(filename)) :])
                self.refuse(f"it includes {filename} inside itself ({cycle})")
            try:
                return original(inp, filename)
            except ExpatError as exc:
                if filename is None or len(getattr(self.module, "filestack", None) or ()) < 2:
                    raise  # the file itself: xacro's message names it
                self.refused = f"the file {filename} it includes is not XML ({exc})"
                raise _Refused(self.refused) from None

        return parse

    def _safe_eval(self, original):
        guard = self

        compiled: dict[str, Any] = {}  # an expression's guarded code, once per text

        def safe_eval(expr, globals, locals=None):
            self.tick()
            text = expr.strip()
            code = compiled.get(text)
            if code is None:
                plain = compile(text, "<expression>", "eval")
                if any(n.startswith("__") for n in plain.co_names):
                    return original(expr, globals, locals)  # xacro's own refusal, in its words
                tree = _Guarded().visit(ast.parse(text, "<expression>", "eval"))
                code = compiled[text] = compile(ast.fix_missing_locations(tree), "<expression>", "eval")
            globals.update(__builtins__={_GUARD: guard._operation, _CALL: guard._call})

            def trace(frame, event, arg):  # every line and loop iteration of the expression's own code
                if frame.f_code.co_filename != "<expression>":
                    guard.tick()  # a function the expression calls (YAML's loader, xacro's lookups): the time
                    return None  # not traced inside
                guard.steps += 1
                if guard.steps > MAX_STEPS:
                    guard.refuse(f"its expressions take more than {MAX_STEPS:,} steps")
                guard.tick()
                return trace

            previous = sys.gettrace()
            sys.settrace(trace)
            try:
                value = eval(code, globals, locals)
            finally:
                sys.settrace(previous)
            if isinstance(value, (list, tuple, dict, set, frozenset)) and _too_big(value):
                guard.refuse(f"the expression {text[:60]!r} makes a value of more than {MAX_ITEMS:,} items or "
                             f"{MAX_VALUE_CHARS:,} characters")  # fmt: skip
            return value

        return safe_eval

    # -- what an expression may make ------------------------------------------------------
    def _operation(self, op: str, a, b):
        """``a op b`` for ``**``, ``<<``, ``*``, ``%`` and ``+``, refused when the result would be too large."""
        if op == "**":
            if _whole(a) and _whole(b) and b > 0 and abs(a) > 1 and b * (abs(a).bit_length() - 1) > MAX_INT_BITS:
                self.refuse(f"an expression raises {_short(a)} to the power {_short(b)}, an integer of more than "
                            f"{MAX_INT_BITS:,} bits")  # fmt: skip
            return a**b
        if op == "<<":
            if _whole(a) and _whole(b) and a != 0 and b + abs(a).bit_length() > MAX_INT_BITS:
                self.refuse(f"an expression shifts {_short(a)} left by {_short(b)}, an integer of more than "
                            f"{MAX_INT_BITS:,} bits")  # fmt: skip
            return a << b
        if op == "+":
            if isinstance(a, (str, bytes)) and isinstance(b, (str, bytes)) and len(a) + len(b) > MAX_VALUE_CHARS:
                self.refuse(f"an expression joins texts into more than {MAX_VALUE_CHARS:,} characters")
            if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)) and len(a) + len(b) > MAX_ITEMS:
                self.refuse(f"an expression joins sequences into more than {MAX_ITEMS:,} items")
            return a + b
        if op == "%":
            if isinstance(a, (str, bytes)):
                self._check_widths(a if isinstance(a, str) else a.decode("latin-1"), "%")
            return a % b
        for seq, n in ((a, b), (b, a)):
            if isinstance(seq, (str, bytes, list, tuple)) and _whole(n) and len(seq) * n > MAX_ITEMS:
                self.refuse(f"an expression repeats a sequence of {len(seq):,} items {_short(n)} times, more than "
                            f"{MAX_ITEMS:,} items")  # fmt: skip
        if _whole(a) and _whole(b) and abs(a).bit_length() + abs(b).bit_length() > MAX_INT_BITS:
            self.refuse(f"an expression multiplies integers into more than {MAX_INT_BITS:,} bits")
        return a * b

    def _call(self, function, *args, **kwargs):
        """``function(*args, **kwargs)``, refused when an argument holds more than
        :data:`MAX_ITEMS` items or :data:`MAX_VALUE_CHARS` characters (shared lists counted at each reference: what
        ``str`` or ``sum`` would walk), or when a method of a text or a sequence would make more
        (``"x".center(n)``, ``"{:>n}".format``, ``replace``, ``expandtabs``)."""
        name = getattr(function, "__name__", "a function")
        for value in (*args, *kwargs.values()):
            if isinstance(value, (list, tuple, dict, set, frozenset)) and _too_big(value):
                self.refuse(f"an expression passes {name}() a value of more than {MAX_ITEMS:,} items or "
                            f"{MAX_VALUE_CHARS:,} characters")  # fmt: skip
        owner = getattr(function, "__self__", None)
        if isinstance(owner, (str, bytes, list, tuple)):
            for value in (*args, *kwargs.values()):
                if _whole(value) and abs(value) > MAX_ITEMS:
                    self.refuse(f"an expression calls {name}({_short(value)}) on a text or sequence, more than "
                                f"{MAX_ITEMS:,} items")  # fmt: skip
            if name in ("format", "format_map") and isinstance(owner, str):
                self._check_widths(owner, "{")
            if isinstance(owner, str) and name in ("replace", "expandtabs"):
                if name == "replace" and len(args) >= 2 and isinstance(args[0], str) and isinstance(args[1], str):
                    old, new = args[0], args[1]
                    count = len(owner) + 1 if not old else owner.count(old)
                    made = len(owner) + count * (len(new) - len(old))
                else:
                    tab = args[0] if args and _whole(args[0]) else kwargs.get("tabsize", 8)
                    made = len(owner) + owner.count("\t") * (tab if _whole(tab) else 8)
                if made > MAX_VALUE_CHARS:
                    self.refuse(f"an expression calls {name}() making {made:,} characters, more than "
                                f"{MAX_VALUE_CHARS:,}")  # fmt: skip
        return function(*args, **kwargs)

    def _check_widths(self, text: str, style: str) -> None:
        """Refuse a format (``{:>N}``, ``%Nd``) whose width or precision exceeds :data:`MAX_ITEMS`."""
        pattern = r"%[-+ #0*]*(\d*)(?:\.(\d*))?" if style == "%" else r"\{[^{}]*:([^{}]*)\}"
        for match in re.finditer(pattern, text):
            for digits in re.findall(r"\d+", " ".join(g or "" for g in match.groups())):
                if len(digits) > 9 or int(digits) > MAX_ITEMS:
                    self.refuse(f"an expression formats with a width or precision of {_short(int(digits[:30]))}"
                                f"{'...' if len(digits) > 30 else ''}, more than {MAX_ITEMS:,} characters")  # fmt: skip

    def _range(self, *args):
        made = range(*args)
        if len(made) > MAX_ITEMS:
            self.refuse(f"an expression makes range({', '.join(map(_short, args))}) of {len(made):,} items, more than "
                        f"{MAX_ITEMS:,}")  # fmt: skip
        return made

    def _count_argument(self, function, name: str):
        def guarded(*args):
            if any(_whole(a) and abs(a) > MAX_TERMS for a in args):
                self.refuse(f"an expression asks for {name}({', '.join(map(_short, args))}), more than {MAX_TERMS:,} "
                            "terms")  # fmt: skip
            return function(*args)

        guarded.__wrapped__ = function  # type: ignore[attr-defined]
        return guarded

    def _product(self, function, name: str):
        """``math.prod`` or ``math.lcm``, refused when the integers' bits add up past :data:`MAX_INT_BITS`."""

        def guarded(*args, **kwargs):
            items = list(args[0]) if name == "math.prod" and args else list(args)
            bits = sum(abs(v).bit_length() for v in items if _whole(v))
            if bits > MAX_INT_BITS:
                self.refuse(f"an expression asks for {name} of integers of {bits:,} bits together, more than "
                            f"{MAX_INT_BITS:,}")  # fmt: skip
            return function(*([items] if name == "math.prod" and args else items), *args[1:], **kwargs)

        guarded.__wrapped__ = function  # type: ignore[attr-defined]
        return guarded

    def _load_yaml(self, original):
        def load_yaml(filename):
            self.tick()
            try:
                size = os.stat(self.module.abs_filename_spec(filename)).st_size
            except (OSError, TypeError, ValueError):
                size = 0  # missing or odd: xacro's own error follows
            if size > MAX_YAML_BYTES:
                self.refuse(f"the YAML file {filename} has {size:,} bytes, more than the {MAX_YAML_BYTES:,} "
                            "xacro.load_yaml reads")  # fmt: skip
            data = original(filename)
            nodes, stack = 0, [data]
            while stack:  # aliases expanded: a shared list counts once per reference
                item = stack.pop()
                nodes += 1
                if nodes > MAX_YAML_NODES:
                    self.refuse(f"the YAML file {filename} holds more than {MAX_YAML_NODES:,} values with its "
                                "aliases expanded")  # fmt: skip
                if isinstance(item, dict):
                    stack.extend(item.values())
                elif isinstance(item, (list, tuple)):
                    stack.extend(item)
            return data

        return load_yaml


def _too_big(value) -> bool:
    """Whether ``value`` holds more than :data:`MAX_ITEMS` items or :data:`MAX_VALUE_CHARS`
    characters, nested containers walked (a shared one at each reference, as ``str`` or ``sum``
    would walk it). A container's items are counted before they are walked, so the walk stops
    after at most :data:`MAX_ITEMS` of them."""
    items, chars, stack = 0, 0, [value]
    while stack:
        item = stack.pop()
        if isinstance(item, (str, bytes)):
            chars += len(item)
            if chars > MAX_VALUE_CHARS:
                return True
        elif isinstance(item, (dict, list, tuple, set, frozenset)):
            items += len(item)
            if items > MAX_ITEMS:
                return True
            stack.extend(item.items() if isinstance(item, dict) else item)
    return False


def _whole(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _short(value) -> str:
    """A number for a message, never thousands of digits."""
    if _whole(value) and abs(value).bit_length() > 64:
        return f"an integer of {abs(value).bit_length():,} bits"
    return repr(value)[:40]


class _Guarded(ast.NodeTransformer):
    """``a ** b``, ``a << b``, ``a * b``, ``a % b`` and ``a + b`` in an expression become calls of the
    guard, every call ``f(...)`` a call of the guard with ``f`` (xacro's lexer ends an expression
    at its first ``}``, so an f-string or a format written out cannot occur; one built from
    pieces is checked when called)."""

    OPERATIONS = {ast.Pow: "**", ast.LShift: "<<", ast.Mult: "*", ast.Mod: "%", ast.Add: "+"}

    def visit_Call(self, node: ast.Call):
        self.generic_visit(node)
        call = ast.Name(id=_CALL, ctx=ast.Load())
        return ast.copy_location(ast.Call(func=call, args=[node.func, *node.args], keywords=node.keywords), node)

    def visit_BinOp(self, node: ast.BinOp):
        self.generic_visit(node)
        op = self.OPERATIONS.get(type(node.op))
        if op is None:
            return node
        guard = ast.Name(id=_GUARD, ctx=ast.Load())
        return ast.copy_location(
            ast.Call(func=guard, args=[ast.Constant(op), node.left, node.right], keywords=[]), node
        )


def split_paths(text: str | None) -> list[Path]:
    """The folders of a ``:``-separated list (``ROS_PACKAGE_PATH``), empty entries dropped."""
    return [Path(part) for part in (text or "").split(os.pathsep) if part.strip()]


def search_roots(package_paths: Iterable[str | Path] = ()) -> list[Path]:
    """Where packages are looked for, in order: ``package_paths``, ``ROS_PACKAGE_PATH``, then
    ``share/`` of each ``AMENT_PREFIX_PATH`` prefix."""
    roots = [Path(p) for p in package_paths]
    roots += split_paths(os.environ.get("ROS_PACKAGE_PATH"))
    roots += [prefix / "share" for prefix in split_paths(os.environ.get("AMENT_PREFIX_PATH"))]
    return list(dict.fromkeys(roots))


def _package_name(folder: Path) -> str | None:
    """The ``<name>`` of the ``package.xml`` in ``folder`` (``None`` without a readable one)."""
    file = folder / "package.xml"
    if file_refusal(file, limit=MAX_ROBOT_FILE_BYTES) is not None:  # a FIFO or device: skipped, not read
        return None
    try:
        name = ElementTree.parse(file).getroot().findtext("name")
    except (OSError, ElementTree.ParseError):
        return None
    return name.strip() if name else None


class _BoundedOpen:
    """xacro's ``open`` while it expands a file: what it reads (the file, its includes, the YAML
    files it loads) must be regular files, of at most :data:`MAX_ROBOT_FILE_BYTES` together, so
    a FIFO or ``/dev/zero`` included is refused at once, not read forever."""

    def __init__(self) -> None:
        self.read = 0
        self.refused: str | None = None

    def __call__(self, file, mode="r", *args, **kwargs):
        if not any(flag in mode for flag in "wax+"):
            reason = file_refusal(file, limit=MAX_ROBOT_FILE_BYTES)
            if reason is None:
                self.read += os.stat(file).st_size
                if self.read > MAX_ROBOT_FILE_BYTES:
                    reason = f"the file and its includes come to more than the {MAX_ROBOT_FILE_BYTES} bytes this reads"
            if reason is not None:
                self.refused = f"{file}: {reason}"
                raise OSError(errno.EINVAL, reason, str(file))
        return open(file, mode, *args, **kwargs)


def find_package(name: str, roots: Iterable[Path]) -> Path | None:
    """The folder of package ``name`` under ``roots`` (see the module docstring), or ``None``."""
    for root in roots:
        if not root.is_dir():
            continue
        if _package_name(root) == name or (root.name == name and _package_name(root) is None):
            return root
        direct = root / name
        if direct.is_dir() and _package_name(direct) in (name, None):
            return direct
        level = [root]
        for _ in range(SEARCH_DEPTH):
            below = []
            for folder in level:
                with contextlib.suppress(OSError):
                    below += sorted(p for p in folder.iterdir() if p.is_dir() and not p.name.startswith("."))
            for folder in below:
                if (folder / "package.xml").is_file() and _package_name(folder) == name:
                    return folder
            level = below
    return None


class _Packages:
    """``$(find PKG)`` for one expansion: each package resolved once, the misses remembered."""

    def __init__(self, roots: list[Path]) -> None:
        self.roots = roots
        self.found: dict[str, Path] = {}
        self.missing: list[str] = []

    def __call__(self, name: str) -> str:
        name = str(name).strip()
        if name not in self.found:
            folder = find_package(name, self.roots)
            if folder is None:
                self.missing.append(name)
                raise LookupError(name)
            self.found[name] = folder.resolve()
        return str(self.found[name])


def expand_xacro(
    path: str | Path,
    xacro_args: Mapping[str, str] | None = None,
    package_paths: Iterable[str | Path] = (),
) -> tuple[str, list[Path]]:
    """The URDF text of a xacro file, and the folders of the packages it found.

    Args:
        path: the ``.xacro`` file.
        xacro_args: values of ``$(arg NAME)``.
        package_paths: folders searched first for ``$(find PKG)``.

    Raises:
        XacroError: the file is missing or malformed, an argument has no value, a package is
            found nowhere, or xacro fails otherwise (its message in one line).
    """
    try:
        import xacro
        from xacro import substitution_args
    except ImportError as exc:  # pragma: no cover - xacro is a dependency
        raise XacroError(str(path), "reading xacro needs the xacro package (pip install xacro)") from exc
    path = Path(path)
    reason = file_refusal(path, limit=MAX_ROBOT_FILE_BYTES)
    if reason is not None:
        raise XacroError(str(path), reason)
    roots = search_roots(package_paths)
    packages = _Packages(roots)
    mappings = {str(k): str(v) for k, v in (xacro_args or {}).items()}
    printed = io.StringIO()
    with _LOCK, contextlib.redirect_stderr(printed), contextlib.redirect_stdout(printed):
        saved = substitution_args._eval_find, substitution_args._eval_dict.get("find")
        substitution_args._eval_find = packages
        substitution_args._eval_dict["find"] = packages
        bounded = _BoundedOpen()
        xacro.open = bounded  # found before the built-in by xacro's own calls to open()
        guard = _Guard(xacro, path.resolve())
        guard.install()
        try:
            document = xacro.process_file(str(path.resolve()), mappings=mappings, verbosity=0)
            text = document.toxml()
            files = [path.resolve(), *(Path(f) for f in xacro.all_includes)]
        except _Refused:
            raise XacroError(str(path), guard.refused or "refused") from None
        except Exception as exc:  # xacro raises its own and Python's exceptions alike
            if bounded.refused is not None:
                raise XacroError(str(path), bounded.refused) from None
            if guard.refused is not None:  # refused inside, then wrapped by xacro
                raise XacroError(str(path), guard.refused) from None
            raise _failure(path, exc, packages, roots, mappings, printed.getvalue()) from None
        finally:
            guard.restore()
            del xacro.open
            substitution_args._eval_find, substitution_args._eval_dict["find"] = saved
            xacro.all_includes.clear()
    _check_arguments(path, mappings, files)
    return text, list(packages.found.values())


_DECLARED = re.compile(r"<xacro:arg\b[^>]*\bname\s*=\s*[\"']([^\"']+)[\"']")
_USED = re.compile(r"\$\(arg\s+([^)\s]+)\s*\)")


def _check_arguments(path: Path, mappings: Mapping[str, str], files: list[Path]) -> None:
    """Refuse a given argument that no file of the expansion declares (``<xacro:arg>``) or uses
    (``$(arg NAME)``): a misspelt name would otherwise be dropped and the robot built with the
    default it meant to change."""
    if not mappings:
        return
    known: set[str] = set()
    for file in files:
        with contextlib.suppress(OSError, UnicodeDecodeError):
            text = file.read_text()
            known |= set(_DECLARED.findall(text)) | set(_USED.findall(text))
    unknown = sorted(set(mappings) - known)
    if unknown:
        has = ", ".join(sorted(known)) or "none"
        raise XacroError(
            str(path),
            f"--xacro-arg {unknown[0]}={mappings[unknown[0]]}: the file neither declares nor uses an argument "
            f"{unknown[0]!r} (its arguments: {has})",
        )


def _failure(path: Path, exc: Exception, packages: _Packages, roots: list[Path], mappings, printed: str) -> XacroError:
    """One XacroError saying what went wrong and what supplies the missing piece."""
    from xacro.substitution_args import ArgException

    if packages.missing:
        where = ", ".join(str(r) for r in roots) or "no folder (none given, ROS_PACKAGE_PATH unset)"
        return XacroError(
            str(path),
            f"$(find {packages.missing[-1]}): package {packages.missing[-1]!r} not found (searched {where}); "
            "give its folder, or a folder holding it, with --package-path DIR (package_paths in a spec, "
            "or ROS_PACKAGE_PATH)",
        )
    cause: Any = exc
    while getattr(cause, "exc", None) is not None and not isinstance(cause, ArgException):
        cause = cause.exc
    if isinstance(cause, ArgException) or "Undefined substitution argument" in str(exc):
        name = str(cause).strip() or str(exc)
        given = ", ".join(sorted(mappings)) or "none"
        return XacroError(
            str(path),
            f"$(arg {name}) has no value and no default: give it with --xacro-arg {name}=VALUE "
            f"([xacro_args] in a spec; given: {given})",
        )
    message = " ".join(str(exc).split()) or type(exc).__name__
    detail = " ".join(line.strip() for line in printed.splitlines() if "when processing file" in line)
    return XacroError(str(path), f"xacro cannot expand it: {message}" + (f" ({detail})" if detail else ""))


def read_xacro(
    path: str | Path,
    *,
    package_dirs: Iterable[str | Path] | None = None,
    xacro_args: Mapping[str, str] | None = None,
    package_paths: Iterable[str | Path] = (),
) -> RobotDescription:
    """Expand a xacro file and read the URDF it gives into a checked description.

    Args:
        path: the ``.xacro`` / ``.urdf.xacro`` file.
        package_dirs: where ``package://`` mesh URIs resolve (default: the file's folder); the
            folders holding the packages ``$(find)`` found are added.
        xacro_args: values of ``$(arg NAME)`` (strings).
        package_paths: folders searched first for ``$(find PKG)`` (see the module docstring).

    Raises:
        XacroError: the expansion fails (see :func:`expand_xacro`).
        UrdfError: the expanded URDF is not a valid robot (naming the link or joint).
    """
    from ..support.files import note_input

    path = Path(path)
    note_input(path)
    text, found = expand_xacro(path, xacro_args, package_paths)
    dirs = [Path(p) for p in package_dirs] if package_dirs is not None else [path.parent]
    dirs += [Path(p) for p in package_paths] + [folder.parent for folder in found]
    return urdf_description(text, path, format="xacro", package_dirs=list(dict.fromkeys(dirs)))


def _read(path: Path, **options: Any) -> RobotDescription:
    return read_xacro(path, **options)


#: The xacro format (suffixes ``.xacro``, ``.urdf.xacro``), registered at import.
FORMAT = register_format(
    DescriptionFormat("xacro", (".xacro", ".urdf.xacro"), _read, ("package_dirs", "xacro_args", "package_paths"))
)
