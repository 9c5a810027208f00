"""Mutation testing of tvist's Python numerics: make small bugs, check the tests catch them.

For each module of ``MODULES`` the AST is searched for mutation sites inside functions
(arithmetic and comparison operators swapped, ``and``/``or`` swapped, a unary minus or
``not`` removed, a numeric constant changed, a boolean constant flipped, an augmented
assignment's operator swapped). A seeded sample of at most ``--per-module`` sites is
mutated one at a time in a private copy of the package (``python/tvist`` with its compiled
extension), and the module's tests run against that copy (``PYTHONPATH`` puts it first).
A mutant is *caught* when the tests fail, *timeout* when they run past ``--timeout-factor``
times the unmutated run (counted as caught: the tests did not pass), and *survived* when they
pass. Mutants that do not compile, or leave the source unchanged, are not viable and are not
counted.

Results go to ``target/mutants-python/results.json`` and a summary is printed; survivors
are listed with their line and change so each can be killed with a test or documented as
equivalent (docs/mutants.md). ``make mutants`` runs this after cargo-mutants.
"""

from __future__ import annotations

import argparse
import ast
import json
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "python" / "tvist"

#: Module (relative to python/tvist) -> the test files that must catch its mutants.
MODULES: dict[str, tuple[str, ...]] = {
    "ident/local_fit.py": (
        "tests/unit/test_ident_local_fit.py",
        "tests/integration/test_ident_base_mode.py",
    ),
    "ident/local_identification.py": (
        "tests/unit/test_ident_local_fit.py",
        "tests/integration/test_ident_base_mode.py",
    ),
    "ident/zoh.py": (
        "tests/unit/test_ident_local_fit.py",
        "tests/integration/test_ident_base_mode.py",
    ),
    "ident/map_fit.py": ("tests/reference/test_ident_map_fit.py",),
    "analysis/residual.py": ("tests/reference/test_analysis.py",),
    "ztdis.py": ("tests/reference/test_zero_delay.py", "tests/unit/test_ztdis_inputs.py"),
}

_BINOP_SWAP = {
    ast.Add: ast.Sub,
    ast.Sub: ast.Add,
    ast.Mult: ast.Div,
    ast.Div: ast.Mult,
    ast.FloorDiv: ast.Div,
    ast.Pow: ast.Mult,
    ast.Mod: ast.Mult,
}
_CMP_SWAP = {
    ast.Lt: ast.LtE,
    ast.LtE: ast.Lt,
    ast.Gt: ast.GtE,
    ast.GtE: ast.Gt,
    ast.Eq: ast.NotEq,
    ast.NotEq: ast.Eq,
    ast.In: ast.NotIn,
    ast.NotIn: ast.In,
    ast.Is: ast.IsNot,
    ast.IsNot: ast.Is,
}


@dataclass(frozen=True)
class Site:
    """One mutation: the ``index``-th candidate node in walk order, and what is done to it."""

    index: int
    line: int
    change: str


def _is_docstring(node: ast.AST, parents: dict[ast.AST, ast.AST]) -> bool:
    parent = parents.get(node)
    return isinstance(parent, ast.Expr) and isinstance(node, ast.Constant)


def _in_function(node: ast.AST, parents: dict[ast.AST, ast.AST]) -> bool:
    while node in parents:
        node = parents[node]
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            return True
    return False


def _mutations(node: ast.AST) -> list[str]:
    """The changes applicable to ``node`` (as descriptions)."""
    if isinstance(node, ast.BinOp) and type(node.op) in _BINOP_SWAP:
        return [f"{type(node.op).__name__} -> {_BINOP_SWAP[type(node.op)].__name__}"]
    if isinstance(node, ast.AugAssign) and type(node.op) in _BINOP_SWAP:
        return [f"{type(node.op).__name__}= -> {_BINOP_SWAP[type(node.op)].__name__}="]
    if isinstance(node, ast.Compare) and len(node.ops) == 1 and type(node.ops[0]) in _CMP_SWAP:
        return [f"{type(node.ops[0]).__name__} -> {_CMP_SWAP[type(node.ops[0])].__name__}"]
    if isinstance(node, ast.BoolOp):
        return ["And -> Or" if isinstance(node.op, ast.And) else "Or -> And"]
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.Not)):
        return [f"drop {type(node.op).__name__}"]
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool):
            return [f"{node.value} -> {not node.value}"]
        if isinstance(node.value, int):
            return [f"{node.value} -> {node.value + 1}"]
        if isinstance(node.value, float):
            return [f"{node.value!r} -> {_changed_float(node.value)!r}"]
    return []


def _changed_float(value: float) -> float:
    return 1.0 if value == 0.0 else value * 1.5


def _apply(node: ast.AST) -> ast.AST:
    """The mutated replacement of ``node`` (the first of :func:`_mutations`)."""
    if isinstance(node, ast.BinOp):
        return ast.BinOp(node.left, _BINOP_SWAP[type(node.op)](), node.right)
    if isinstance(node, ast.AugAssign):
        return ast.AugAssign(node.target, _BINOP_SWAP[type(node.op)](), node.value)
    if isinstance(node, ast.Compare):
        return ast.Compare(node.left, [_CMP_SWAP[type(node.ops[0])]()], node.comparators)
    if isinstance(node, ast.BoolOp):
        return ast.BoolOp(ast.Or() if isinstance(node.op, ast.And) else ast.And(), node.values)
    if isinstance(node, ast.UnaryOp):
        return node.operand
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool):
            return ast.Constant(not node.value)
        if isinstance(node.value, int):
            return ast.Constant(node.value + 1)
        return ast.Constant(_changed_float(node.value))
    raise AssertionError(node)


def candidates(tree: ast.Module) -> list[tuple[ast.AST, str]]:
    """Every mutable node inside a function, in a deterministic walk order."""
    parents = {child: parent for parent in ast.walk(tree) for child in ast.iter_child_nodes(parent)}
    out = []
    for node in ast.walk(tree):
        if not _in_function(node, parents) or _is_docstring(node, parents):
            continue
        if isinstance(node, ast.Constant) and isinstance(parents.get(node), ast.JoinedStr):
            continue
        if isinstance(parents.get(node), ast.FormattedValue):
            continue  # the value formatted into an error message
        out.extend((node, change) for change in _mutations(node))
    return out


def mutate(source: str, index: int) -> tuple[str, Site]:
    """``source`` with its ``index``-th candidate mutated."""
    tree = ast.parse(source)
    node, change = candidates(tree)[index]
    replacement = ast.copy_location(_apply(node), node)
    parents = {child: parent for parent in ast.walk(tree) for child in ast.iter_child_nodes(parent)}
    parent = parents[node]
    for field, value in ast.iter_fields(parent):
        if value is node:
            setattr(parent, field, replacement)
        elif isinstance(value, list):
            for i, item in enumerate(value):
                if item is node:
                    value[i] = replacement
    ast.fix_missing_locations(tree)
    return ast.unparse(tree), Site(index, getattr(node, "lineno", 0), change)


def run_tests(copy_root: Path, tests: tuple[str, ...], timeout_s: float | None) -> str:
    """``"passed"``, ``"failed"`` or ``"timeout"`` for the tests against the copy."""
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(copy_root), os.environ.get("PYTHONPATH", "")]),
        "PYTHONDONTWRITEBYTECODE": "1",
        "MPLBACKEND": "Agg",
    }
    cmd = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", *tests]
    try:
        proc = subprocess.run(
            cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout_s
        )
    except subprocess.TimeoutExpired:
        return "timeout"
    return "passed" if proc.returncode == 0 else "failed"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--per-module", type=int, default=25, help="mutants sampled per module")
    parser.add_argument("--seed", type=int, default=17)
    parser.add_argument("--timeout-factor", type=float, default=3.0)
    parser.add_argument("--module", action="append", help="only these modules (repeatable)")
    parser.add_argument(
        "--site",
        action="append",
        default=[],
        help="MODULE:INDEX, run only these mutation sites (repeatable), e.g. to re-check "
        "survivors after adding tests",
    )
    parser.add_argument("--out", type=Path, default=ROOT / "target" / "mutants-python")
    args = parser.parse_args(argv)

    only: dict[str, list[int]] = {}
    for item in args.site:
        module, index = item.rsplit(":", 1)
        only.setdefault(module, []).append(int(index))
    selected = args.module or list(only)
    modules = {m: t for m, t in MODULES.items() if not selected or m in selected}
    args.out.mkdir(parents=True, exist_ok=True)
    results: dict[str, dict] = {}
    with tempfile.TemporaryDirectory(prefix="tvist-mutants-") as tmp:
        copy_root = Path(tmp)
        shutil.copytree(PACKAGE, copy_root / "tvist", ignore=shutil.ignore_patterns("__pycache__"))
        for module, tests in modules.items():
            target = copy_root / "tvist" / module
            original = (PACKAGE / module).read_text()
            start = time.monotonic()
            if run_tests(copy_root, tests, None) != "passed":
                print(f"{module}: the tests fail without a mutant; fix them first")
                return 1
            baseline_s = time.monotonic() - start
            sites = candidates(ast.parse(original))
            rng = random.Random(f"{args.seed}:{module}")
            chosen = sorted(rng.sample(range(len(sites)), min(args.per_module, len(sites))))
            if module in only:
                chosen = sorted(only[module])
            outcome = {"sites": len(sites), "baseline_s": baseline_s, "mutants": []}
            for index in chosen:
                mutated, site = mutate(original, index)
                if mutated == ast.unparse(ast.parse(original)):
                    continue
                try:
                    compile(mutated, module, "exec")
                except SyntaxError:
                    continue
                target.write_text(mutated)
                status = run_tests(copy_root, tests, args.timeout_factor * baseline_s + 30.0)
                target.write_text(original)
                outcome["mutants"].append({**asdict(site), "status": status})
                print(f"{module}:{site.line} [{index}] {site.change}: {status}", flush=True)
            results[module] = outcome
    summary = []
    total_caught = total = 0
    for module, outcome in results.items():
        viable = outcome["mutants"]
        caught = sum(m["status"] != "passed" for m in viable)
        total_caught += caught
        total += len(viable)
        survivors = [
            f"{m['line']} [site {m['index']}]: {m['change']}"
            for m in viable
            if m["status"] == "passed"
        ]
        summary.append(f"{module}: {caught}/{len(viable)} caught (of {outcome['sites']} sites)")
        summary.extend(f"    survived line {s}" for s in survivors)
    (args.out / "results.json").write_text(json.dumps(results, indent=2))
    print("\n".join(summary))
    if total:
        print(
            f"python numerics: {total_caught}/{total} = {100 * total_caught / total:.0f} % caught"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
