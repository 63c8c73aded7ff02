"""Exceptions raised at the API boundary."""


class MeshError(ValueError):
    """Invalid mesh input: the message names the problem and the offending ids."""


def format_ids(ids, limit=10):
    """``"3, 17, 42 (and 5 more)"`` for error messages."""
    ids = [int(i) for i in ids]
    head = ", ".join(str(i) for i in ids[:limit])
    return head + (f" (and {len(ids) - limit} more)" if len(ids) > limit else "")


class AccuracyWarning(UserWarning):
    """The inputs are valid but round-off will cost accuracy (e.g. a penalty far above E_solid)."""


class CouplingWarning(UserWarning):
    """A beam of a coupled scene is not coupled to the solid (e.g. it lies outside it)."""


class LargeDeformationWarning(UserWarning):
    """A linear analysis moved a body by a sizeable fraction of its own size: linear kinematics is
    not valid there (often a unit slip, e.g. E in MPa in a scene in metres)."""
