"""``calstation`` command lines, each run in a process forked from one that loaded only the
entry point: what each imported of the heavy libraries, and its exit status.

Run as ``python -m tests.forked_cli`` with a JSON list of argument lists on standard
input; prints a JSON object: ``base`` the heavy modules the entry point itself loaded,
and ``runs`` for each argument list its exit status and the heavy modules it loaded on
top. Each command line costs its own imports only, not the interpreter's start and the
entry point's (most of ``calstation --help``): the suite checks some fifty of them.
Only the standard library and the entry point are imported here before forking.
"""

import json
import os
import sys

from station.cli.main import main

#: What a one-line answer must not wait for: the numerics, the database and
#: web layers, the station's loop and the report renderer.
HEAVY = ("numpy", "scipy", "matplotlib", "sqlalchemy", "fastapi", "station.loop", "station.report")


def heavy_loaded() -> list[str]:
    """The heavy modules this process has imported."""
    return sorted(
        name for name in sys.modules for h in HEAVY if name == h or name.startswith(f"{h}.")
    )


def _run_forked(args: list[str]) -> dict[str, object]:
    """``calstation ARGS`` in a forked child, its output discarded."""
    read_end, write_end = os.pipe()
    child = os.fork()
    if child == 0:  # the child: run the command, report, and end without cleanup
        os.close(read_end)
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        sys.argv = ["calstation", *args]
        status = 0
        try:
            main()
        except SystemExit as stop:
            status = stop.code if isinstance(stop.code, int) else int(stop.code is not None)
        except BaseException:  # any other end is a status the test names (-1)
            status = -1
        with os.fdopen(write_end, "w") as report:
            json.dump({"status": status, "heavy": heavy_loaded()}, report)
        os._exit(0)
    os.close(write_end)
    with os.fdopen(read_end) as report:
        answer: dict[str, object] = json.load(report)
    os.waitpid(child, 0)
    return answer


if __name__ == "__main__":
    command_lines = json.load(sys.stdin)
    base = heavy_loaded()
    json.dump({"base": base, "runs": [_run_forked(args) for args in command_lines]}, sys.stdout)
