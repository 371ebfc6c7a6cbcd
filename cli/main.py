"""The ``bushing`` command line: the model's commands (:mod:`cli.commands`) and ``serve``, which starts
the explorer. The arrow points one way: the app extends the core's command line, the core never
imports the app."""

from __future__ import annotations

import argparse
import sys

from . import commands
from . import parser as cli_parser
from .commands import InputError


def build_parser() -> argparse.ArgumentParser:
    parser = cli_parser.build_parser()
    sv = cli_parser.subcommands(parser).add_parser(
        "serve",
        help="start the explorer in the browser (embedded defaults, no setup)",
        description="Start the Bushing Explorer web app and print its URL.",
    )
    sv.add_argument("--port", type=cli_parser._count("--port", 0), default=5006, metavar="P", help="default 5006")
    sv.add_argument(
        "--address", default="localhost", metavar="A",
        help="interface to listen on (default localhost; 0.0.0.0 for every interface)",
    )
    sv.add_argument(
        "--max-sessions", type=cli_parser._count("--max-sessions", 1, 10000), default=None, metavar="N",
        help="sessions this process holds at once; a new page beyond is told the server is busy "
             "(default 40, see docs/serving.md)",
    )
    return parser


def _cmd_serve(args) -> None:
    if args.port > 65535:
        raise InputError(f"bushing serve: --port must be at most 65535, got {args.port}")
    from app.main import serve  # Panel and the explorer: imported only when asked for

    limits = {} if args.max_sessions is None else {"max_sessions": args.max_sessions}
    try:
        serve(port=args.port, address=args.address, **limits)
    except OSError as exc:
        raise InputError(f"bushing serve: cannot listen on {args.address}:{args.port}: {exc.strerror}")


COMMANDS = {**commands.COMMANDS, "serve": _cmd_serve}


def main(argv: list[str] | None = None) -> int:
    return commands.main(argv, build_parser(), COMMANDS)


if __name__ == "__main__":
    sys.exit(main())
