"""The method registry as a user sees it."""

import pendulab as pl


def test_printing_the_registry_lists_every_method_by_family():
    text = repr(pl.METHODS)
    assert "object at 0x" not in text and text.startswith(f"<{len(pl.METHODS)} integration methods")
    for name, spec in pl.METHODS.items():
        assert name in text and f"{spec.family}:" in text
