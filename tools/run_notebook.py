#!/usr/bin/env python3
"""Executes a notebook headless, as CI does for examples/quickstart.ipynb: every cell in order
with a fresh Python 3 kernel (Debian's python3-nbclient and python3-ipykernel), failing on the
first error; the executed notebook (outputs included) is written to --output.

    python3 tools/run_notebook.py examples/quickstart.ipynb -o build/quickstart.executed.ipynb

Exit 0: every cell ran; 1: a cell raised (its traceback is printed); 77: nbclient or ipykernel
is not installed (ctest counts that as skipped unless SOFTEVO_REQUIRE_NOTEBOOK=1, which
tools/bootstrap.sh test sets after installing them).
"""

import argparse
import os
import pathlib
import sys


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("notebook", type=pathlib.Path)
    parser.add_argument("-o", "--output", type=pathlib.Path, required=True)
    parser.add_argument("--timeout", type=int, default=300, help="seconds per cell")
    args = parser.parse_args()
    try:
        import nbclient
        import nbformat
        import ipykernel  # noqa: F401  (the kernel nbclient starts)
    except ImportError as e:
        print(f"run_notebook: {e}: install python3-nbclient and python3-ipykernel",
              file=sys.stderr)
        return 1 if os.environ.get("SOFTEVO_REQUIRE_NOTEBOOK") == "1" else 77
    nb = nbformat.read(args.notebook, as_version=4)
    # The kernel is this interpreter (the one the softevo package was built for), matplotlib
    # draws into the notebook without a display.
    os.environ["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"
    # The kernel runs in the notebook's folder: relative PYTHONPATH entries (build/python) must
    # still find the package.
    os.environ["PYTHONPATH"] = os.pathsep.join(
        os.path.abspath(p) for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p)
    os.environ.setdefault("PYDEVD_DISABLE_FILE_VALIDATION", "1")  # the kernel's debugger notes
    client = nbclient.NotebookClient(
        nb, timeout=args.timeout, kernel_name="python3",
        resources={"metadata": {"path": str(args.notebook.resolve().parent)}})
    try:
        client.execute()
    except nbclient.exceptions.CellExecutionError as e:
        print(f"run_notebook: {args.notebook}: a cell failed:\n{e}", file=sys.stderr)
        nbformat.write(nb, args.output)
        return 1
    nbformat.write(nb, args.output)
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if o.get("output_type") == "error"]
    if errors:
        print(f"run_notebook: {args.notebook}: {len(errors)} error outputs", file=sys.stderr)
        return 1
    print(f"run_notebook: {args.notebook}: {sum(c.cell_type == 'code' for c in nb.cells)} code "
          f"cells ran; executed notebook in {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
