"""Shared pytest fixtures."""

from __future__ import annotations

import os

import pytest

import gltf_validator


@pytest.fixture(scope="session")
def gltf_validate():
    """``validate(path) -> report``: the Khronos glTF-Validator.

    A missing validator is a loud skip on a developer's machine and a failure under CI
    (the CI environment variable set): in CI a missing tool is an install bug, never a pass.
    """
    reason = gltf_validator.unavailable_reason()
    if reason is not None:
        if os.environ.get("CI"):
            pytest.fail(f"CI: {reason}", pytrace=False)
        pytest.skip(f"SKIPPED, NOT VALIDATED: {reason}")
    return gltf_validator.validate_gltf
