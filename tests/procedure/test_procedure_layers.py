"""gyrodrift.procedure in layers (issue 9 §3): algorithms -> results <- writers and figures, no circle.

The algorithms import only the results, the time line, each other along the pipeline and the core; never the
writers, the figures, matplotlib or gyrodrift.files.atomic. They run without matplotlib and without a file system.
"""

import ast
import subprocess
import sys
import textwrap
from pathlib import Path

import gyrodrift.procedure

PACKAGE = Path(gyrodrift.procedure.__file__).parent
ALGORITHMS = ("align", "passes", "truth", "features", "evaluate", "identify")
OUTPUTS = ("writers", "figures")
RESULTS = ("results", "best_law")
"""The result types: they import no algorithm, only each other."""


def _imports(module: str) -> set[str]:
    """Every module `module` imports, at the top or inside functions (TYPE_CHECKING blocks too)."""
    tree = ast.parse((PACKAGE / f"{module}.py").read_text())
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module:
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
    return found


def test_algorithms_never_import_outputs_matplotlib_or_the_file_writer():
    for module in ALGORITHMS:
        imported = _imports(module)
        for other in OUTPUTS:
            assert f"gyrodrift.procedure.{other}" not in imported, f"{module} imports {other}"
        assert not any(m.startswith("matplotlib") for m in imported), module
        assert "gyrodrift.files.atomic" not in imported, module


def test_results_import_no_algorithm_and_outputs_import_only_results():
    for module in RESULTS:
        procedure = {m.rsplit(".", 1)[1] for m in _imports(module) if m.startswith("gyrodrift.procedure")}
        assert procedure <= set(RESULTS), f"{module} imports {procedure}"
    for module in OUTPUTS:
        used = {m.rsplit(".", 1)[1] for m in _imports(module) if m.startswith("gyrodrift.procedure.")}
        assert used <= {*RESULTS, "figures"}, f"{module} imports {used}"


def test_the_import_graph_has_no_circle():
    modules = [p.stem for p in PACKAGE.glob("*.py") if p.stem != "__init__"]
    edges = {
        m: {i.rsplit(".", 1)[1] for i in _imports(m) if i.startswith("gyrodrift.procedure.")} & set(modules)
        for m in modules
    }
    done, active = set(), []

    def visit(m):
        assert m not in active, " -> ".join(active + [m])
        if m in done:
            return
        active.append(m)
        for n in edges[m]:
            visit(n)
        active.pop()
        done.add(m)

    for m in modules:
        visit(m)


def test_an_algorithm_runs_without_matplotlib_and_without_files(tmp_path):
    code = textwrap.dedent(
        """
        import os, sys
        sys.modules["matplotlib"] = None  # any import of matplotlib fails
        from gyrodrift.ins.scenario import Scenario
        from gyrodrift.ins.simulate import scenario_log
        from gyrodrift.procedure import evaluate_compensation
        scenario = Scenario.from_dict({"run": {"duration_h": 4.25, "rate_hz": 2.0},
                                       "gyro": {"bias_deg_h": [0.0, 0.0, 0.003]}})
        ev = evaluate_compensation(scenario_log(scenario), 0.003, hours=0.25)
        assert ev.after.final_nmi < ev.before.final_nmi, (ev.before.final_nmi, ev.after.final_nmi)
        assert sys.modules["matplotlib"] is None and "matplotlib.figure" not in sys.modules
        assert os.listdir(".") == []
        print("ok", ev.before.final_nmi, ev.after.final_nmi)
        """
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout.startswith("ok"), done.stderr
