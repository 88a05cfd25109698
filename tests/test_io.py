"""Atomic writes: complete files or nothing, the usual file mode, no temporary files left behind."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from amigo_gym.io import atomic_save, atomic_write, atomic_write_json, file_mode


def test_atomic_write_text_bytes_json(tmp_path: Path) -> None:
    atomic_write(tmp_path / "a.txt", "héllo\n")
    atomic_write(tmp_path / "b.bin", b"\x00\x01")
    atomic_write_json(tmp_path / "sub" / "c.json", {"x": [1, 2]}, parents=True)
    assert (tmp_path / "a.txt").read_text(encoding="utf-8") == "héllo\n"
    assert (tmp_path / "b.bin").read_bytes() == b"\x00\x01"
    assert json.loads((tmp_path / "sub" / "c.json").read_text()) == {"x": [1, 2]}
    assert (os.stat(tmp_path / "a.txt").st_mode & 0o777) == file_mode()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.txt", "b.bin", "sub"]


def test_interrupted_save_keeps_the_old_file_and_leaves_no_temporary(tmp_path: Path) -> None:
    target = tmp_path / "model.zip"
    target.write_bytes(b"old")

    def broken_save(tmp: str) -> None:
        Path(tmp).write_bytes(b"half")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_save(broken_save, target)
    assert target.read_bytes() == b"old"
    assert [p.name for p in tmp_path.iterdir()] == ["model.zip"]


def test_missing_folder_is_an_error_unless_parents(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="does not exist"):
        atomic_write(tmp_path / "nope" / "x.txt", "x")
    atomic_write(tmp_path / "yes" / "x.txt", "x", parents=True)
    assert (tmp_path / "yes" / "x.txt").read_text() == "x"


def test_suffix_kept_for_format_sniffing_writers(tmp_path: Path) -> None:
    seen: list[str] = []
    atomic_save(lambda tmp: (seen.append(tmp), Path(tmp).write_bytes(b"png")), tmp_path / "fig.png")
    assert seen[0].endswith(".png")
