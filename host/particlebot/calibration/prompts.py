"""Asking the person at the bench, without letting the swarm go unattended while they answer."""

from __future__ import annotations

import sys
import threading
from collections.abc import Callable

from particlebot.errors import ParticlebotError

KEEP_ALIVE_S = 0.2
"""How often the swarm is looked after while a person thinks about an answer."""


class NobodyAnswers(ParticlebotError):  # noqa: N818 (reads as what happened)
    """The prompt's input is closed (no terminal, or a file of answers that ran out)."""


class Quit(ParticlebotError):  # noqa: N818 (reads as what happened)
    """The person asked to stop (q)."""


class Prompter:
    """Asks questions and returns the line typed (stripped).

    With `ask` (a test, or answers prepared in code) each question is answered at once. Without
    it, input() reads the terminal (or whatever stdin is) on a thread of its own, so that
    keep_alive() goes on every KEEP_ALIVE_S meanwhile: a held servo is renewed, the radio read
    and logged, a simulation stepped in time with the wall clock. Ctrl-C reaches the caller.
    """

    def __init__(self, ask: Callable[[str], str] | None = None) -> None:
        self._ask = ask

    def ask(self, prompt: str, keep_alive: Callable[[], None] | None = None) -> str:
        if self._ask is not None:
            try:
                return self._ask(prompt).strip()
            except EOFError:
                raise NobodyAnswers from None
        answer: list[str] = []
        closed: list[bool] = []
        done = threading.Event()

        def read() -> None:
            try:
                answer.append(input(prompt))
            except (EOFError, OSError, ValueError, RuntimeError):  # closed, or no stdin at all
                closed.append(True)
            finally:
                done.set()

        threading.Thread(target=read, name="calibration-prompt", daemon=True).start()
        while not done.wait(KEEP_ALIVE_S):
            if keep_alive is not None:
                keep_alive()
        if closed:
            print()  # the prompt's line ends here, not in the next message
            raise NobodyAnswers
        if sys.stdin is not None and not sys.stdin.isatty():
            print(answer[0])  # answers from a file: the transcript shows what was answered
        return answer[0].strip()

    def confirm(self, prompt: str, keep_alive: Callable[[], None] | None = None) -> None:
        """Waits for Enter; q (or quit) raises Quit."""
        if self.ask(prompt, keep_alive).lower() in ("q", "quit"):
            raise Quit
