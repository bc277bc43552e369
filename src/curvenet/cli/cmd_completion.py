"""``curvenet completion SHELL``: print the shell code that completes curvenet's commands."""

from __future__ import annotations

#: Shells argcomplete writes completion code for.
SHELLS = ("bash", "zsh", "fish", "tcsh", "powershell")


def register(sub) -> None:
    p = sub.add_parser(
        "completion",
        help="print shell completion code (bash, zsh, fish...; needs argcomplete, extra cli)",
        description="Print the code that makes the shell complete curvenet's commands, options and "
                    "file names (argcomplete). Load it in the shell's start-up file, e.g. "
                    'eval "$(curvenet completion bash)" in ~/.bashrc.',
    )
    p.add_argument("shell", choices=SHELLS, help="the shell")
    p.set_defaults(func=run)


def run(args) -> int:
    from ..errors import require

    argcomplete = require("argcomplete", "shell completion", "cli")
    print(argcomplete.shellcode(["curvenet"], shell=args.shell), end="")
    return 0
