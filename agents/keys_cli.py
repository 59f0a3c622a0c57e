"""``faultmas keys generate DIR NAME...``: Ed25519 key pairs for the secure profile (docs/reliability.md).

Writes ``DIR/NAME.key`` (private, mode 0600: copy it only to the host that runs NAME) and ``DIR/NAME.pub``
(list it in the project: ``NAME NAME.asl [key="DIR/NAME.pub"];`` or ``[key="DIR"]`` for a whole folder).
The same files can be made with ``openssl genpkey -algorithm ed25519`` and ``openssl pkey -pubout``.
"""
from __future__ import annotations

import argparse
import sys


def add_keys_parser(sub: argparse._SubParsersAction) -> None:
    """Register ``faultmas keys`` on the CLI dispatcher's sub-parsers."""
    keys = sub.add_parser("keys", help="make Ed25519 key pairs for the secure profile",
                          description=__doc__.splitlines()[0])
    keys_sub = keys.add_subparsers(dest="keys_command", metavar="ACTION")
    generate = keys_sub.add_parser("generate", help="write DIR/NAME.key and DIR/NAME.pub for each NAME")
    generate.add_argument("directory", metavar="DIR", help="where the key files go (created if missing)")
    generate.add_argument("names", metavar="NAME", nargs="+", help="agent names")
    generate.set_defaults(func=cmd_keys_generate)
    keys.set_defaults(func=lambda args: (keys.print_help(), 2)[1])


def cmd_keys_generate(args: argparse.Namespace) -> int:
    from agents.transport.identity import IdentityError, generate_keys
    from agents.transport.keys import check_name

    try:
        for name in args.names:
            check_name(name)
        written = generate_keys(args.directory, args.names)
    except (IdentityError, ValueError) as exc:
        print(f"faultmas keys generate: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"faultmas keys generate: {exc.filename}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    for path in written:
        print(path)
    return 0
