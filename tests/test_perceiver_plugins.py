"""Perceivers as plugins: a ``capmj.perceivers`` entry point declared by another distribution is
a perception mode of the bench, the agents and the envs.

Nothing is installed: the test writes a plugin module and its distribution's metadata
(``<dist>.dist-info`` with ``METADATA`` and ``entry_points.txt``, what pip would write) into a temp
folder and puts the folder on ``sys.path``; :mod:`importlib.metadata` finds it like any installed
distribution.
"""

from __future__ import annotations

import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

from capmj.agents.reference import ReferenceAgent
from capmj.bench.cli import build_parser
from capmj.errors import ConfigError, PluginError
from capmj.perception.plugins import declared, load_perceiver, perception_modes, source_tree_entry_points
from capmj.runner import run_episode
from capmj.tasks.registry import get_task

PLUGIN = '''
"""A third-party perceiver: the built-in one behind a wrapper that counts its calls."""
from capmj.perception import ClassicalPerceiver

CALLS = []


class CountingPerceiver:
    def __init__(self):
        self.inner = ClassicalPerceiver()

    def perceive(self, bundle):
        CALLS.append(len(bundle.views))
        return self.inner.perceive(bundle)


class NotAPerceiver:
    pass
'''


@pytest.fixture()
def plugin_site(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    site = tmp_path / "site"
    (site / "demo_perceiver").mkdir(parents=True)
    (site / "demo_perceiver" / "__init__.py").write_text(textwrap.dedent(PLUGIN))
    info = site / "capmj_demo_perceiver-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: capmj-demo-perceiver\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[capmj.perceivers]\ncounting = demo_perceiver:CountingPerceiver\n"
                                           "hollow = demo_perceiver:NotAPerceiver\n")
    monkeypatch.syspath_prepend(str(site))
    yield site
    sys.modules.pop("demo_perceiver", None)


def test_a_perceiver_declared_by_another_distribution_runs_an_episode(plugin_site: Path) -> None:
    assert perception_modes() == ("state", "rgbd", "counting", "hollow")
    assert "demo_perceiver" not in sys.modules  # listing modes imports no plugin
    r = run_episode(get_task("put-block-into-matching-bowl"), 10003, ReferenceAgent(perception="counting"))
    assert r.success, (r.error, r.diagnostics)
    calls = sys.modules["demo_perceiver"].CALLS
    assert len(calls) == r.primitives + 1 and set(calls) == {3}  # reset + after every move, three views each
    assert r.perception is not None and r.perception.perceiver == "counting"
    assert len(r.perception.calls) == len(calls)


def test_bad_and_unknown_perceivers_are_named(plugin_site: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(PluginError, match=r"perceiver 'hollow' .*capmj-demo-perceiver.* no perceive\(bundle\)"):
        load_perceiver("hollow")
    with pytest.raises(ConfigError, match="valid modes: state, rgbd, counting, hollow"):
        load_perceiver("lidar")
    with pytest.raises(ConfigError, match="valid modes"):
        load_perceiver("state")  # the simulator is a mode, not a perceiver
    assert build_parser().parse_args(["--perception", "counting"]).perception == "counting"
    with pytest.raises(SystemExit):
        build_parser().parse_args(["--perception", "lidar"])
    assert "unknown perception mode 'lidar'; valid modes: state, rgbd, counting, hollow" in capsys.readouterr().err


def test_without_plugins_the_modes_are_capmj_own() -> None:
    assert perception_modes()[:2] == ("state", "rgbd")
    assert type(load_perceiver("rgbd")).__name__ == "ClassicalPerceiver"


def _capmj_metadata(site: Path, entry_points: str) -> None:
    """A capmj distribution's metadata on ``site`` (found before the installed one)."""
    info = site / "capmj-0.1.0.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: capmj\nVersion: 0.1.0\n")
    (info / "entry_points.txt").write_text(entry_points)


def test_capmj_declares_rgbd_in_its_pyproject_and_the_source_tree_reads_it() -> None:
    root = Path(__file__).resolve().parents[1]
    project = tomllib.loads((root / "pyproject.toml").read_text())["project"]
    assert project["entry-points"]["capmj.perceivers"] == {"rgbd": "capmj.perception.perceiver:ClassicalPerceiver"}
    assert [(e.name, e.value) for e in source_tree_entry_points(root)] == [
        ("rgbd", "capmj.perception.perceiver:ClassicalPerceiver")]
    assert source_tree_entry_points(root / "tests") == ()  # no pyproject there: nothing


def test_stale_capmj_metadata_falls_back_to_the_source_tree(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """An install made before the entry point existed declares no perceiver: the checkout's
    pyproject.toml supplies capmj's, and unknown names still list the valid modes."""
    _capmj_metadata(tmp_path, "[capmj.tasks]\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    eps, own = declared()
    assert own == {"rgbd"} and getattr(eps["rgbd"], "dist", None) is None  # from the pyproject, not metadata
    assert perception_modes() == ("state", "rgbd")
    assert type(load_perceiver("rgbd")).__name__ == "ClassicalPerceiver"
    with pytest.raises(ConfigError, match="unknown perception mode 'sonar'; valid modes: state, rgbd$"):
        load_perceiver("sonar")


def test_current_capmj_metadata_is_what_names_the_perceiver(plugin_site: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Where capmj's metadata declares its perceivers, they come from there (here a metadata that
    points ``rgbd`` elsewhere, to prove it), and a plugin cannot take one of their names."""
    site = plugin_site.parent / "capmj-site"
    _capmj_metadata(site, "[capmj.perceivers]\nrgbd = demo_perceiver:CountingPerceiver\n")
    (plugin_site / "capmj_demo_perceiver-0.1.dist-info" / "entry_points.txt").write_text(
        "[capmj.perceivers]\nrgbd = demo_perceiver:NotAPerceiver\ncounting = demo_perceiver:CountingPerceiver\n")
    monkeypatch.syspath_prepend(str(site))
    assert perception_modes() == ("state", "rgbd", "counting")
    assert type(load_perceiver("rgbd")).__name__ == "CountingPerceiver"
