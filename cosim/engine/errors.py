"""The one kind of error a user's mistake raises.

Every mistake in what a user gives (a file, a value in it, a setting, an argument) is an
`InputError` whose message is one line naming the place (file and line, or the setting or
argument) and the reason: the command line prints it and exits 2, the Python API raises it. Each
kind of input has its own subclass (SceneError, SspError, SettingsError, SweepError, StudyError).
"""

from __future__ import annotations


class InputError(ValueError):
    """A mistake in the user's input: the message is one line naming where and why."""


class UsageError(InputError):
    """A command-line argument or API argument that does not apply or has a wrong value."""


class SspError(InputError):
    """An SSP file that cannot be read or run: the message names the file, and the line where known."""
