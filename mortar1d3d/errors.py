"""Exceptions raised at the API boundary."""


class MeshError(ValueError):
    """Invalid mesh input: the message names the problem and the offending ids."""


def format_ids(ids, limit=10):
    """``"3, 17, 42 (and 5 more)"`` for error messages."""
    ids = [int(i) for i in ids]
    head = ", ".join(str(i) for i in ids[:limit])
    return head + (f" (and {len(ids) - limit} more)" if len(ids) > limit else "")
