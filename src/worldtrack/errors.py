"""Errors a user can cause and fix.

Every exception that is the user's input at fault (a scene file, a CSV, a video) derives from
:class:`InputError`. The command line prints its message on one line (``error: …``) and exits
with status 2; anything else is a bug and keeps its traceback.
"""

from __future__ import annotations


class InputError(ValueError):
    """Bad input from the user: the message names the file, the field and what was expected."""


class SceneError(InputError):
    """A scene file failed validation.

    Parameters
    ----------
    problems : list of str
        One line per problem, each ``file: field.path: what was expected``.
    """

    def __init__(self, problems: list[str]):
        self.problems = list(problems)
        super().__init__("; ".join(self.problems))
