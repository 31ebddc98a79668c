"""Scenes shipped with pendulab (TOML files read by :mod:`pendulab.scene`)."""
