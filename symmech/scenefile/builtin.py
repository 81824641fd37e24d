"""The built-in scene files shipped in ``symmech/scenes/``."""

from __future__ import annotations

import importlib.resources
import os
from pathlib import Path

from symmech.scenefile.format import (
    _IDENTIFIER,
    _SCENES_FOLDER,
    _SCENES_PACKAGE,
    SceneFileError,
    _clip,
    _did_you_mean,
)

# ---------------------------------------------------------------------------------------
# built-in scene files


def builtin_scene_names() -> list[str]:
    """Names of the scene files shipped in ``symmech/scenes/`` (sorted)."""
    folder = importlib.resources.files(_SCENES_PACKAGE).joinpath(_SCENES_FOLDER)
    if not folder.is_dir():
        return []
    return sorted(p.name[: -len(".toml")] for p in folder.iterdir() if p.name.endswith(".toml"))


def builtin_scene_path(name: str) -> Path:
    """The path of the shipped scene file ``name`` (e.g. ``"carnot_3_7"``).

    Raises :class:`SceneFileError` naming the built-in scenes if there is none.
    """
    names = builtin_scene_names()
    if name not in names:
        hint = _did_you_mean(name, names)
        raise SceneFileError(
            [
                f"no scene file {_clip(name)!r} and no built-in scene of that name{hint};"
                f" built-in: {names}"
            ]
        )
    resource = importlib.resources.files(_SCENES_PACKAGE).joinpath(_SCENES_FOLDER, f"{name}.toml")
    return Path(str(resource))


def _resolve_path(path: str | os.PathLike[str]) -> Path:
    p = Path(path)
    text = os.fspath(path)
    if p.is_file() or (p.exists() and text not in builtin_scene_names()):
        return p
    if _IDENTIFIER.match(text):
        return builtin_scene_path(text)
    raise SceneFileError([f"{text}: no such scene file"], path=text)
