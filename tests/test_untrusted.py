"""Pickles load only when trusted (issue 37): the seven crafted cases run no payload without ``--trust-unverified``
(each refused in one line naming the file and the flag) and run it with the flag (the payloads are live); the
shipped agents load without it.

A payload is an object whose unpickling creates a marker folder (``os.mkdir``). Trusted means: a sha256 a shipped
manifest records, one a run of this installation wrote (``amigo_gym.io.vouch``, into this test's state folder),
or the user's flag; a sha256 in a manifest beside the file is not enough (whoever made the file made it too).
"""

from __future__ import annotations

import base64
import json
import os
import pickle
import shutil
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from cli_here import Ran

from amigo_gym.data import pretrained_dir
from amigo_gym.io import STATE_ENV, TRUST_ENV, UntrustedFileError, sha256_file

FLAG = "--trust-unverified"


class Payload:
    def __init__(self, marker: Path) -> None:
        self.marker = str(marker)

    def __reduce__(self) -> tuple[Any, ...]:
        return os.mkdir, (self.marker,)


def crafted_zip(genuine: Path, dest: Path, marker: Path) -> Path:
    """``genuine`` (an SB3 zip) with a payload as its serialized observation space."""
    with zipfile.ZipFile(genuine) as z:
        parts = {n: z.read(n) for n in z.namelist()}
    data = json.loads(parts["data"])
    data["observation_space"][":serialized:"] = base64.b64encode(pickle.dumps(Payload(marker))).decode()
    parts["data"] = json.dumps(data).encode()
    dest.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(dest, "w") as z:
        for n, b in parts.items():
            z.writestr(n, b)
    return dest


@pytest.fixture(autouse=True)
def _own_state(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(STATE_ENV, str(tmp_path / "state"))
    monkeypatch.delenv(TRUST_ENV, raising=False)


def refused(r: Ran, name: str) -> None:
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1, (r.returncode, r.stdout[-300:], r.stderr)
    assert name in lines[0] and FLAG in lines[0] and "refused" in lines[0], lines[0]


def test_seven_crafted_pickles_run_nothing_without_the_flag(tmp_path: Path, in_process: Callable[..., Ran]) -> None:
    markers = [tmp_path / f"ran{k}" for k in range(1, 8)]
    shipped = pretrained_dir()
    quick = ["--no-plots", "--seeds", "1", "--steps", "5"]
    cases: list[tuple[str, list[str]]] = []  # (the file the refusal names, the command)

    # 1, 2: a crafted model zip given to evaluate as a folder, and as a file
    crafted_zip(shipped / "ppo.zip", tmp_path / "c1" / "ppo.zip", markers[0])
    cases.append(("ppo.zip", ["evaluate", "--models", str(tmp_path / "c1"), "--out", str(tmp_path / "o1"), *quick]))
    z2 = crafted_zip(shipped / "td3.zip", tmp_path / "c2" / "td3.zip", markers[1])
    cases.append(("td3.zip", ["evaluate", "--models", str(z2), "--out", str(tmp_path / "o2"), *quick]))

    # 3: to benchmark --agents (a manifest beside it with its own sha256 does not make it trusted)
    z3 = crafted_zip(shipped / "v1" / "td3lp" / "td3lp_s0.zip", tmp_path / "c3" / "td3lp_s0.zip", markers[2])
    manifest = json.loads((shipped / "v1" / "td3lp" / "td3lp_s0.json").read_text()) | {"sha256": sha256_file(z3)}
    z3.with_suffix(".json").write_text(json.dumps(manifest))
    bench = ["--scenarios", "lane_change", "--no-plots", "--no-progress", "--reps", "10", "--profile-reps", "10"]
    cases.append(("td3lp_s0.zip", ["benchmark", "--agents", f"mine={z3}", "--out", str(tmp_path / "o3"), *bench]))

    # 4: the genuine, hash-verified sac.zip with a crafted vecnormalize.pkl beside it
    (tmp_path / "c4").mkdir()
    for name in ("sac.zip", "sac.json"):
        shutil.copy(shipped / name, tmp_path / "c4" / name)
    (tmp_path / "c4" / "vecnormalize.pkl").write_bytes(pickle.dumps(Payload(markers[3])))
    cases.append(
        (
            "vecnormalize.pkl",
            ["evaluate", "--models", str(tmp_path / "c4" / "sac.zip"), "--out", str(tmp_path / "o4"), *quick],
        )
    )

    # 5: train --resume with a re-hashed replay buffer (the checkpoint's meta.json rewritten to match it)
    from test_train import hp_file

    train = ["train", "--no-progress", "--algo", "td3", "--out", str(tmp_path / "c5"), "--eval-freq", "0"]
    train += ["--hyperparams", hp_file(tmp_path, "td3"), "--checkpoint-freq", "150"]
    assert in_process(*train, "--timesteps", "150").returncode == 0
    (ck,) = (tmp_path / "c5" / "checkpoints").iterdir()
    (ck / "replay_buffer.pkl").write_bytes(pickle.dumps(Payload(markers[4])))
    meta = json.loads((ck / "meta.json").read_text())
    meta["files"]["replay_buffer.pkl"] = sha256_file(ck / "replay_buffer.pkl")
    (ck / "meta.json").write_text(json.dumps(meta))
    cases.append(("replay_buffer.pkl", [*train, "--timesteps", "300", "--resume"]))

    # 6: train-fast --resume with a crafted checkpoint (torch.load of a pickle)
    import torch

    (tmp_path / "c6").mkdir()
    torch.save({"settings": Payload(markers[5])}, tmp_path / "c6" / "checkpoint.pt")
    cases.append(("checkpoint.pt", ["train-fast", "--out", str(tmp_path / "c6"), "--resume"]))

    # 7: load_pretrained (Python) on a crafted zip whose manifest records its sha256
    z7 = crafted_zip(shipped / "sac.zip", tmp_path / "c7" / "sac.zip", markers[6])
    z7.with_suffix(".json").write_text(json.dumps({"algo": "sac", "sha256": sha256_file(z7)}))

    def python_api(flag: list[str]) -> Ran:
        from amigo_gym.policies import load_pretrained

        try:
            load_pretrained(z7, trust=bool(flag))
        except UntrustedFileError as exc:
            return Ran(2, "", f"{exc}\n")
        except Exception as exc:  # the payload ran; what SB3 does with what it returned does not matter
            return Ran(1, "", f"{type(exc).__name__}: {exc}")
        return Ran(0, "", "")

    def run(case: tuple[str, list[str]], flag: list[str]) -> Ran:
        return in_process(*case[1], *flag) if case[1] else python_api(flag)

    cases.append(("sac.zip", []))
    for case, marker in zip(cases, markers, strict=True):
        refused(run(case, []), case[0])
        assert not marker.exists(), case[0]
    assert not [m for m in markers if m.exists()]  # 0 payloads ran
    for case, marker in zip(cases, markers, strict=True):  # the flag loads them: the payloads are live
        run(case, [FLAG])
        assert marker.exists(), f"{case[0]}: the payload did not run with {FLAG}"


def test_shipped_and_own_files_load_without_the_flag(tmp_path: Path) -> None:
    from amigo_gym.policies import load_pretrained
    from amigo_gym.tools.training.evaluate import PRETRAINED_DIR, load_agents

    assert set(load_agents(PRETRAINED_DIR)) == {"ppo", "sac", "td3"}
    for z in sorted(pretrained_dir().glob("v1/*/*_s0.zip")):
        assert load_pretrained(z) is not None
    # a shipped model copied elsewhere is still the shipped file
    shutil.copy(pretrained_dir() / "td3.zip", tmp_path / "td3.zip")
    assert set(load_agents(tmp_path / "td3.zip")) == {"td3"}
