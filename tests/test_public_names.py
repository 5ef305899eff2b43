"""``dir(kinprop)`` lists the public API, not the helpers the package imports (issue 19 item 11)."""

from __future__ import annotations

import kinprop


def test_dir_is_the_public_api():
    public = [n for n in dir(kinprop) if not n.startswith("_")]
    assert public == sorted(kinprop.__all__)
    assert not {"Any", "TYPE_CHECKING", "importlib"} & set(dir(kinprop))
    assert all(getattr(kinprop, n) is not None for n in kinprop.__all__)
