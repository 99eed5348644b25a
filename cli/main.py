"""The ``cgamesh`` command.

    cgamesh SCENE.yaml -o OUT.glb [...]      build meshes and export them (cli/build.py)
    cgamesh COMMAND ...                       one of the subcommands in SUBCOMMANDS:
    cgamesh check FILE [...]                  mesh-quality report of a scene or exported file (cli/check.py)
    cgamesh view SCENE.yaml -o PAGE.html      a self-contained viewer page (cli/view.py)
    cgamesh render SCENE.yaml -o IMAGE.png    ray trace the analytic surfaces (cli/render.py)
    cgamesh verify SCENE.yaml MESH.glb        mesh against the ray tracer (cli/verify.py)
    cgamesh batch INPUT... -o OUTDIR          many inputs on Dask, resumable (cli/batch.py)

Thin by design: each command module parses its arguments and calls the package; this module
dispatches, and turns any CgameshError into one line on stderr with exit status 2. No geometry
lives here, and nothing heavy is imported before a command needs it.
"""

from __future__ import annotations

import importlib
import sys

from cgamesh import __version__
from cgamesh.errors import CgameshError

EXIT_USER_ERROR = 2
# subcommand name -> module of this package with build_parser() and run(args) -> str | None
SUBCOMMANDS: dict[str, str] = {"check": "check", "view": "view", "render": "render", "verify": "verify",
                               "batch": "batch"}


def main(argv: list[str] | None = None) -> int:
    from cgamesh import interrupts

    previous = interrupts.install()
    try:
        return _main(argv)
    except (interrupts.Interrupted, KeyboardInterrupt) as stop:
        from cgamesh.export.atomic import remove_live_temporaries

        remove_live_temporaries()
        print("cgamesh: interrupted", file=sys.stderr)
        return getattr(stop, "exit_status", 130)
    finally:
        interrupts.restore(previous)


def _main(argv: list[str] | None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv == ["--version"]:
        print(f"cgamesh {__version__}")
        return 0
    name = argv[0] if argv and argv[0] in SUBCOMMANDS else None
    module = importlib.import_module(f"cgamesh_cli.{SUBCOMMANDS[name]}" if name else "cgamesh_cli.build")
    try:
        parser = module.build_parser()  # may consult the input table, and so import its plugins
        parser.error = _refuse_usage(parser.prog)  # argparse's own prints the whole usage: one line, as every error
        args = parser.parse_args(argv[1:] if name else argv)
        result = module.run(args)
    except (CgameshError, _UsageError) as error:
        print(f"cgamesh: error: {error}", file=sys.stderr)
        return EXIT_USER_ERROR
    if isinstance(result, int):
        return result
    if result and not getattr(args, "quiet", False):
        print(result)
    return 0


class _UsageError(Exception):
    """A command line argparse refuses (unknown flag, bad value); exit status 2 like other mistakes."""


def _refuse_usage(prog: str):
    def refuse(message: str):
        raise _UsageError(f"{message} (see {prog} --help)")

    return refuse


if __name__ == "__main__":
    sys.exit(main())
