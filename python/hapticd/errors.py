"""The package's exceptions: a refusal by the daemon apart from a broken transport."""

from __future__ import annotations


class HapticdError(Exception):
    """Base of every error this package raises, so one ``except`` catches them all."""


class ClientError(HapticdError):
    """The socket or the state block failed: nothing was learnt about the request's fate."""


class StateError(ClientError):
    """The state block is not the layout this package reads (magic, version, sizes)."""


class Refused(HapticdError):
    """The daemon answered ``ok: false``: the request changed nothing.

    ``code`` is the exit code the daemon assigns (2 malformed/invalid, 3 refused by the
    passivity gate, 1 anything else), so a script can pass it on as its own exit status.
    """

    def __init__(self, error: str, code: int, *, cmd: str | None = None,
                 socket_path: str | None = None) -> None:
        self.error = error
        self.code = code
        self.cmd = cmd
        self.socket_path = socket_path
        where = f"{socket_path}: " if socket_path else ""
        what = f"{cmd} " if cmd else ""
        super().__init__(f"{where}{what}refused (code {code}): {error}")
