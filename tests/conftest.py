"""Shared fixtures: one renderer for the whole run, paths to models, golden-image options."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import SHARED_MODELS, TESTS

import blueprint.api
from blueprint import Renderer

ARTIFACTS = TESTS / "_artifacts"


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--regen-goldens",
        action="store_true",
        help="rewrite the golden images in tests/golden/ from the current renderer",
    )


@pytest.fixture(scope="session")
def renderer():
    """One GL context for the session, also the one ``blueprint.render`` and friends use, so
    tests need not care which context is current; every test must leave no GL error behind."""
    with Renderer() as r:
        previous, blueprint.api._renderer = blueprint.api._renderer, r
        yield r
        blueprint.api._renderer = previous


@pytest.fixture(autouse=True)
def _no_gl_errors(request):
    if "renderer" in request.fixturenames:
        request.getfixturevalue("renderer").make_current()
    yield
    if "renderer" in request.fixturenames:
        r = request.getfixturevalue("renderer")
        r.make_current()
        assert r.ctx.error == "GL_NO_ERROR"


@pytest.fixture(scope="session")
def shared_models() -> Path:
    """The shared test models (present in CI); tests using them skip where they are absent."""
    if not SHARED_MODELS.is_dir():
        pytest.skip(f"shared models not found at {SHARED_MODELS} (a fresh clone has none)")
    return SHARED_MODELS


@pytest.fixture(scope="session")
def artifacts() -> Path:
    """Where tests leave images for a person to look at (diffs of failed goldens)."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    return ARTIFACTS
