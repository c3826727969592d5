"""Errors a user can fix: the CLI prints them as one line and exits with status 2."""

from __future__ import annotations


class UserError(Exception):
    """A mistake in the input (a study file, a command line, a missing piece of the project)."""


class StudyError(UserError, ValueError):
    """A study file that does not validate; the message names the file and the key path."""

    def __init__(self, file, path: str, message: str):
        self.file, self.path, self.message = str(file), path, message
        where = f"{self.file}: {path}: " if path else f"{self.file}: "
        super().__init__(where + message)


class Unavailable(UserError, RuntimeError):
    """A part of jaxrender the study needs is missing: a pipeline that is not registered, a
    camera path that gives the wrong number of cameras."""
