"""Configurations as a grid axis and the capability profile (#49 items 1, 2, 4, 7): the tier table and
user TOML files, a paired table whose McNemar counts are counted by hand, a multi-configuration run
into one folder that resumes, report refusing runs whose task stamps differ, and the measured
reporter defaults."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from capmj.bench.cli import build_parser, main
from capmj.bench.config import BenchConfig, Given
from capmj.bench.configs import TIERS, Configuration, available_options, load_file, merged, resolve
from capmj.bench.profile import profile
from capmj.bench.stamp import mismatches
from capmj.bench.stats import mcnemar_exact
from capmj.errors import ConfigError
from capmj.records import EpisodeRecord
from capmj.resources import prompts_dir

TASK = "put-block-into-matching-bowl"


# ---------------------------------------------------------------------- the tiers and user files
def test_unknown_configurations_are_refused_by_the_names_of_the_valid_ones() -> None:
    with pytest.raises(ConfigError, match=r"unknown configuration\(s\) S9; valid: S1, S2, S3, S4, M1, M2, M3, T1, "
                                          r"R1, thesis \(add your own with --configs-file"):
        resolve("S1,S9")
    with pytest.raises(ConfigError, match="named twice"):
        resolve("S1,S1")


def test_a_tier_is_refused_exactly_while_the_flag_table_lacks_its_option() -> None:
    flags = set(available_options())
    for tier in TIERS:
        needs = {k for k, v in tier.options.items() if k not in flags and not (k == "api" and v == "high")
                 and not (k == "perception" and v == "state")}
        if needs:
            with pytest.raises(ConfigError, match=f"needs option '{sorted(needs)[0]}'|needs option"):
                resolve(tier.name)
        else:
            assert resolve(tier.name)[0].name == tier.name
    # S1 asks for what the agent does without options: nothing is passed, with any agent
    assert resolve("S1")[0].options == {}


def test_every_available_tier_builds_the_llm_agent_with_its_options() -> None:
    from capmj.agents.factory import agent_setting, make_agent

    shared = {"model": "openai/stub", "api_base": "http://127.0.0.1:9/v1"}
    for tier in TIERS:
        try:
            (config,) = resolve(tier.name)
        except ConfigError:
            continue  # its option has not landed yet (the test above)
        configs = BenchConfig.resolve(Given(agent="llm", agent_options=shared, configs=(config,))).configs
        agent = make_agent("llm", **configs[0].options)
        for key, value in tier.options.items():
            assert agent_setting(agent, key, value) == value, (tier.name, key)


def test_a_user_file_adds_configurations_extending_tiers(tmp_path: Path) -> None:
    path = tmp_path / "mine.toml"
    path.write_text('[configs.rgbd-loop]\nabout = "perceived, with a reporter"\nextends = "S2"\nreporter = "text"\n'
                    'attempts = 3\n\n[configs.warp]\nwarp_drive = "on"\n\n[configs.bad]\nreporter = "oracle"\n')
    mine = load_file(path)
    assert [c.name for c in mine] == ["rgbd-loop", "warp", "bad"]
    (loop,) = resolve("rgbd-loop", mine)
    assert loop.options == {"perception": "rgbd", "reporter": "text", "attempts": 3}
    with pytest.raises(ConfigError, match="needs option 'warp_drive'.*does not have yet"):
        resolve("warp", mine)
    with pytest.raises(ConfigError, match="reporter='oracle' is not one of none, text, vlm"):
        resolve("bad", mine)
    with pytest.raises(ConfigError, match="unknown configuration.*valid: S1.*rgbd-loop, warp, bad"):
        resolve("nope", mine)
    with pytest.raises(ConfigError, match="not valid TOML"):
        (tmp_path / "broken.toml").write_text("[configs.x\n")
        load_file(tmp_path / "broken.toml")


def test_a_configuration_and_the_command_line_may_not_disagree() -> None:
    r1 = resolve("R1")[0]
    assert merged(r1, {"model": "m", "reporter": "text"}) == {"model": "m", **r1.options}
    with pytest.raises(ConfigError, match="configuration 'R1' sets reporter='text' but the command line gives "
                                          "reporter='vlm'"):
        merged(r1, {"reporter": "vlm"})
    # an option left out because the agent does it anyway still may not be overridden
    with pytest.raises(ConfigError, match="configuration 'S1' sets perception='state' but the command line gives "
                                          "perception='rgbd'"):
        merged(resolve("S1")[0], {"perception": "rgbd"})


# ---------------------------------------------------------------------- item 7: the measured defaults
def test_a_reporter_gets_the_loop_measured_never_to_hurt_and_the_thesis_loop_stays_a_tier() -> None:
    config = BenchConfig.resolve(Given(agent="llm", agent_options={"model": "m", "reporter": "text"}))
    assert config.agent_options["loop_policy"] == "careful" and config.agent_options["reporter_prompt"] == "relations"
    told = BenchConfig.resolve(Given(agent="llm", agent_options={"model": "m", "reporter": "text",
                                                                 "loop_policy": "thesis"}))
    assert told.agent_options["loop_policy"] == "thesis" and told.agent_options["reporter_prompt"] == "relations"
    without = BenchConfig.resolve(Given(agent="llm", agent_options={"model": "m"}))
    assert "loop_policy" not in without.agent_options  # no reporter: the two loops are the same
    tiers = BenchConfig.resolve(Given(agent="llm", agent_options={"model": "m"}, configs=resolve("thesis,R1")))
    assert [dict(c.options) for c in tiers.configs] == [
        {"model": "m", "reporter": "text", "loop_policy": "thesis", "reporter_prompt": "thesis"},
        {"model": "m", "reporter": "text", "loop_policy": "careful", "reporter_prompt": "relations"}]
    # a resume runs on with what the run started with (a run from before keeps the thesis loop)
    earlier = BenchConfig("A", "1", "llm", {"model": "m", "reporter": "text"}, config.execution)
    assert "loop_policy" not in BenchConfig.resolve(Given(), earlier).agent_options
    helps = build_parser().format_help()
    assert "careful" in helps and "relations" in helps and "thesis" in helps


# ---------------------------------------------------------------------- the profile, counted by hand
def _rec(config: str, task: str, seed: int, success: bool, failure: str | None = None) -> EpisodeRecord:
    return EpisodeRecord(task, seed, "llm", "m", success, float(success), 0.0, 1, 1, 1.0, 10.0,
                         None if failure != "llm_error" else "LLMError: down", failure=failure, config=config)


def test_the_paired_table_counts_both_discordant_directions() -> None:
    # seeds 1..8 of task t: A solves 1-5, B solves 4-7; seed 8 is an anomaly of B (left unpaired)
    recs = []
    for s in range(1, 9):
        recs.append(_rec("A", "t", s, s <= 5, None if s <= 5 else "wrong_plan"))
        if s == 8:
            recs.append(_rec("B", "t", s, False, "llm_error"))
        else:
            recs.append(_rec("B", "t", s, 4 <= s <= 7, None if 4 <= s <= 7 else "wrong_plan"))
    recs.append(_rec("C", "t", 1, True))  # C ran one seed only
    prof = profile(recs, lambda r: str(r.config))
    assert prof["configs"] == ["A", "B", "C"] and prof["baseline"] == "A"
    ab = prof["paired"][0]
    assert (ab["a"], ab["b"]) == ("A", "B")
    # pairs 1..7: both 4, 5; only A 1, 2, 3; only B 6, 7; neither none
    pair = ab["overall"]
    assert (pair["n"], pair["successes_a"], pair["successes_b"], pair["only_a"], pair["only_b"]) == (7, 5, 4, 3, 2)
    assert pair["p_value"] == pytest.approx(1.0) == mcnemar_exact(3, 2)  # 2 * P[X <= 2 | 5, 1/2] = 2 * 16/32
    assert ab["unpaired"] == 1  # seed 8: B's anomaly
    assert prof["paired"][1]["overall"]["n"] == 1 and prof["paired"][1]["unpaired"] == 7
    assert prof["overall"]["B"]["denominator"] == "4/7 episodes, 1 anomaly excluded"
    eff = prof["efficiency"]["B"]
    assert (eff["episodes"], eff["solved"]) == (7, 4)
    assert eff["per_episode"]["wall_s"] == pytest.approx(10.0) and eff["per_solved"]["wall_s"] == pytest.approx(70 / 4)


def test_a_configuration_that_solves_nothing_has_no_cost_per_solved_episode() -> None:
    prof = profile([_rec("A", "t", 1, False, "wrong_plan")], lambda r: str(r.config))
    assert prof["efficiency"]["A"]["per_solved"]["wall_s"] is None


# ---------------------------------------------------------------------- a real grid of two configurations
def _grid(out: Path, *extra: str) -> int:
    return main(["--agent", "reference", "--tasks", TASK, "--seeds", "10001:10005:2", "--out", str(out),
                 "--no-progress", "--no-log", "--workers", "0", *extra])


@pytest.fixture(scope="module")
def two_configs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The reference plans under S1 and a user configuration whose sandbox reads the cameras."""
    root = tmp_path_factory.mktemp("profile")
    (root / "mine.toml").write_text('[configs.seen]\nextends = "S2"\n')
    assert _grid(root / "run", "--configs", "S1,seen", "--configs-file", str(root / "mine.toml")) == 0
    return root / "run"


def _lines(run: Path) -> list[dict]:
    return [json.loads(x) for x in (run / "episodes.jsonl").read_text().splitlines() if x.strip()]


def test_every_configuration_runs_the_same_episodes_into_one_folder(two_configs: Path) -> None:
    lines = _lines(two_configs)
    assert sorted((r["config"], r["seed"]) for r in lines) == [("S1", 10001), ("S1", 10003), ("seen", 10001),
                                                               ("seen", 10003)]
    summary = json.loads((two_configs / "summary.json").read_text())
    prof = summary["profile"]
    assert prof["configs"] == ["S1", "seen"] and summary["configs"]["seen"]["options"] == {"perception": "rgbd"}
    outcome = {(r["config"], r["seed"]): r["success"] for r in lines}  # counted by hand from the records
    only_a = sum(outcome["S1", s] and not outcome["seen", s] for s in (10001, 10003))
    only_b = sum(outcome["seen", s] and not outcome["S1", s] for s in (10001, 10003))
    cell = prof["paired"][0]["overall"]
    assert (cell["n"], cell["only_a"], cell["only_b"]) == (2, only_a, only_b)
    assert cell["successes_a"] == sum(outcome["S1", s] for s in (10001, 10003))
    cfg = json.loads((two_configs / "config.json").read_text())
    assert [c["name"] for c in cfg["args"]["configs"]] == ["S1", "seen"]
    assert summary["stamp"]["overall"] == cfg["stamp"]["overall"] and TASK in cfg["stamp"]["tasks"]
    assert "## Capability profile: efficiency" in (two_configs / "summary.md").read_text()


def test_a_multi_configuration_run_resumes_what_is_missing(two_configs: Path, tmp_path: Path,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    run = tmp_path / "run"
    shutil.copytree(two_configs, run)
    kept = [x for x in (run / "episodes.jsonl").read_text().splitlines()
            if not (json.loads(x)["config"] == "seen" and json.loads(x)["seed"] == 10003)]
    (run / "episodes.jsonl").write_text("\n".join(kept) + "\n")  # as if killed before its last episode
    capsys.readouterr()
    assert main(["--out", str(run), "--resume", "--no-progress"]) == 0
    assert "2 configuration(s) (S1, seen) × 1 task(s) × 2 seed(s) = 4 episode(s)" in capsys.readouterr().err
    keys = sorted((r["config"], r["seed"]) for r in _lines(run))
    assert keys == sorted((c, s) for c in ("S1", "seen") for s in (10001, 10003))  # each exactly once
    # a resume naming one more configuration runs only its episodes, and config.json says so
    assert main(["--out", str(run), "--resume", "--no-progress", "--configs", "S1,seen,S3", "--configs-file",
                 str(two_configs.parent / "mine.toml")]) == 0
    assert "4 already done, 2 to run" in capsys.readouterr().err
    assert sorted((r["config"], r["seed"]) for r in _lines(run)) == sorted(
        (c, s) for c in ("S1", "seen", "S3") for s in (10001, 10003))
    change = json.loads((run / "config.json").read_text())["resumes"][-1]["changed"]["configs"]
    assert [c["name"] for c in change["to"]] == ["S1", "seen", "S3"]
    assert json.loads((run / "summary.json").read_text())["profile"]["configs"] == ["S1", "seen", "S3"]


def test_report_refuses_runs_whose_task_stamps_differ(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    assert _grid(tmp_path / "a", "--configs", "S1", "--seeds", "10001") == 0
    edited = tmp_path / "prompts"
    shutil.copytree(prompts_dir(), edited)
    with open(edited / "system.txt", "a") as f:
        f.write("\nBe brief.\n")
    monkeypatch.setenv("CAPMJ_PROMPTS_DIR", str(edited))
    assert _grid(tmp_path / "b", "--configs", "S2", "--seeds", "10001") == 0
    monkeypatch.delenv("CAPMJ_PROMPTS_DIR")
    assert _grid(tmp_path / "c", "--configs", "S2", "--seeds", "10001") == 0
    capsys.readouterr()
    assert main(["report", str(tmp_path / "a"), str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert "prompt folder stamps differ" in err and "--allow-version-mismatch" in err
    assert f"task {TASK}" not in err  # the task itself did not change
    assert main(["report", str(tmp_path / "a"), str(tmp_path / "b"), "--allow-version-mismatch", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["stamp_mismatches"] and list(summary["profile"]["configs"]) == ["S1", "S2"]
    # the same task set: one profile from separate runs, each column named by its configuration
    assert main(["report", str(tmp_path / "a"), str(tmp_path / "c"), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["profile"]["configs"] == ["S1", "S2"] and "stamp_mismatches" not in summary
    assert summary["profile"]["paired"][0]["overall"]["n"] == 1
    # the oracle reads no prompt: its column stays comparable with runs under edited prompts
    assert main(["--agent", "oracle", "--tasks", TASK, "--seeds", "10001", "--out", str(tmp_path / "o"),
                 "--no-progress", "--no-log", "--workers", "0"]) == 0
    assert json.loads((tmp_path / "o" / "config.json").read_text())["stamp"]["prompts"] is None
    capsys.readouterr()
    assert main(["report", str(tmp_path / "o"), str(tmp_path / "a"), str(tmp_path / "b"), "--json"]) == 2
    assert main(["report", str(tmp_path / "o"), str(tmp_path / "b"), "--json"]) == 0


def test_a_changed_task_module_names_the_code() -> None:
    a = {"capmj": "1", "mjcf": "m", "prompts": "p", "tasks": {"t": {"stamp": "x1", "code": "c1"}, "u": {"stamp": "y"}}}
    b = {"capmj": "1", "mjcf": "m", "prompts": "p", "tasks": {"t": {"stamp": "x2", "code": "c2"}, "u": {"stamp": "y"}}}
    assert mismatches({"a": a, "b": b}, ["t", "u"]) == ["task t: stamps differ (a=x1, b=x2); differing: code"]
    assert mismatches({"a": a, "b": None}, ["t"]) == ["b: no task stamp (a run from before stamps were recorded)"]


def test_a_configuration_name_must_be_usable_as_a_folder() -> None:
    with pytest.raises(ConfigError, match="without commas, slashes"):
        Configuration("a/b")
