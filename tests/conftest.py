"""Shared test settings."""

from hypothesis import settings

# Property tests call into Rust: keep them deterministic and quick in CI.
settings.register_profile("rainuav", max_examples=60, deadline=None, derandomize=True)
settings.load_profile("rainuav")
