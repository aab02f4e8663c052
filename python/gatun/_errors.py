"""The exceptions of gatun: one per category of failure, all gatun.Error (a RuntimeError).

Their message is the one `gtn` prints after "gtn: error: " (file, place, reason).
"""


class Error(RuntimeError):
    """A Gatun operation failed."""


class InvalidDataError(Error, ValueError):
    """The input is malformed or violates an invariant (gtn exit code 1)."""


class UnsupportedError(Error, ValueError):
    """A valid input uses a feature Gatun rejects (gtn exit code 1)."""


class NotOurFileError(Error, ValueError):
    """The file is not a .gtn file (gtn exit code 1)."""


class VersionTooNewError(Error, ValueError):
    """The file has a newer major version of the format (gtn exit code 1)."""


class UsageError(Error, ValueError):
    """The call asked for something impossible (gtn exit code 2)."""


class IoError(Error, OSError):
    """A file could not be opened, read or written (gtn exit code 3)."""


class DamagedChunkWarning(UserWarning):
    """A chunk that a read did not need fails its checksum (the text `gtn` prints after "gtn: warning: ")."""
