"""Where the shipped ``agents/`` data live (pretrained models, hyperparameter files): the top-level folder of a
checkout, or ``amigo_gym/agents/`` in a wheel. Imports only the standard library."""

from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent


def repository_root() -> Path | None:
    """The source checkout holding this package (``None`` when installed from a wheel)."""
    root = _PACKAGE.parent
    return root if (root / "pyproject.toml").is_file() and (root / "agents").is_dir() else None


def agents_dir() -> Path:
    """The ``agents/`` data folder: ``amigo_gym/agents`` in a wheel, ``<repository>/agents`` in a checkout
    (``FileNotFoundError`` if neither exists)."""
    installed = _PACKAGE / "agents"
    if installed.is_dir():
        return installed
    if (root := repository_root()) is not None:
        return root / "agents"
    raise FileNotFoundError(f"the agents data folder is missing: neither {installed} nor a source checkout")


def pretrained_dir() -> Path:
    """Folder of the pretrained models and their manifests (``agents/pretrained``)."""
    return agents_dir() / "pretrained"


def hyperparams_dir() -> Path:
    """Folder of the rl-zoo hyperparameter files (``agents/hyperparams``)."""
    return agents_dir() / "hyperparams"
