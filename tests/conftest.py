"""Shared pytest setup. Markers (slow, browser, cluster) are declared in pyproject.toml."""
