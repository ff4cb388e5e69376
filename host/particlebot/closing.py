"""One base for the objects a `with` block closes (radios, simulated swarms, simavr processes)."""

from __future__ import annotations

from types import TracebackType
from typing import Self


class ClosedOnExit:
    """`with thing:` closes the thing when the block ends, however it ends. Subclasses define
    close(); one that must do more on the way out (the API's Swarm stops a run) writes its own."""

    def close(self) -> None:
        raise NotImplementedError

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
