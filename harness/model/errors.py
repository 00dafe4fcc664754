"""The one error a bad model file raises."""
from __future__ import annotations

from pathlib import Path


class ModelFileError(ValueError):
    """A model file that cannot be used as it is; the message names the file and the problem.

    The command line maps it to exit status 2.
    """

    def __init__(self, source: str | Path | None, problem: str):
        self.source = str(source) if source is not None else "<model>"
        self.problem = problem
        super().__init__(f"{self.source}: {problem}")
