"""Models trained in the app live in its own folder (`<user_dir>/models`), apart from the shipped
ones; the registry finds both (shipped first), serves either, and never lets an app model shadow
a shipped one."""

from __future__ import annotations

import shutil
from pathlib import Path

from server.services.corpus import Corpus
from server.services.models import ModelRegistry, user_models
from server.settings import Settings


def test_the_registry_serves_shipped_and_app_models_shipped_first(settings: Settings, tmp_path: Path) -> None:
    app = Settings(
        models_dir=settings.models_dir, corpus_path=settings.corpus_path, user_dir=tmp_path / "user"
    )
    shipped = sorted(p.name for p in settings.models_dir.iterdir())
    shutil.copytree(settings.models_dir / shipped[0], user_models(app) / "mine")
    shutil.copytree(settings.models_dir / shipped[1], user_models(app) / shipped[0])  # a shipped name
    registry = ModelRegistry.serving(app, Corpus.load(app))
    assert registry.names() == [*shipped, "mine"]
    assert registry.get(shipped[0]).path == settings.models_dir / shipped[0]  # not shadowed
    assert registry.select("mine").path == tmp_path / "user" / "models" / "mine"
    assert registry.served.name == "mine"
