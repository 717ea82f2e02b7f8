"""Screenshots of a failed episode in the real rerun viewer, headless (for docs/replay.md).

    python docs/make_screenshots.py                 # record the example failure, write docs/replay_*.png
    python docs/make_screenshots.py EP.rrd --out shots/

Without an ``.rrd`` argument the script records the example failure first: the LLM agent on
put-block-into-matching-bowl seed 10001, its plan scripted through the local stub server of the
tests (a fixture, not a model result): it puts the brown block into the cyan bowl, the yellow
block into the yellow bowl, then asks for the position of an object that does not exist on line 5.

The viewer runs as ``rerun --headless`` (software Vulkan works: apt ``mesa-vulkan-drivers``) and
is driven with ``rerun.experimental.ViewerClient``: wait for the file to paint, save a screenshot;
then show the attempt document and the middle of the last primitive for the second one.
Screenshots are scaled to ``--width`` and palette-quantised to stay small in git.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TASK, SEED = "put-block-into-matching-bowl", 10001
PLAN = '''say("putting each block into its bowl")
put_first_on_second("movable small brown block with obj_id 4", "fixed cyan bowl with obj_id 2")
put_first_on_second("movable small yellow block with obj_id 5", "fixed yellow bowl with obj_id 3")
say("checking the green bowl")
pos = get_obj_pos("fixed green bowl with obj_id 6")
'''


def record_example(path: Path) -> Path:
    """The example failed LLM episode (scripted completion from the tests' stub server)."""
    sys.path.insert(0, str(ROOT / "tests"))
    from llm_stub_server import StubLLMServer

    from capmj.agents.llm_agent.agent import LLMAgent
    from capmj.llm import LLMConfig
    from capmj.runner import record_episode
    from capmj.tasks.registry import get_task

    with StubLLMServer() as server:
        server.script(f"```python\n{PLAN}```")
        agent = LLMAgent(LLMConfig("openai/stub", api_base=server.base_url, api_key="sk-local"))  # one attempt
        result = record_episode(get_task(TASK), SEED, agent, path)
    print(f"recorded {path}: success={result.success} error={result.error} diagnostics={list(result.diagnostics)}")
    return path


def _viewer(port: int, size: str, workdir: Path, rrd: Path) -> subprocess.Popen:
    from capmj.replay.viewer import viewer_command

    cmd = viewer_command()
    if cmd is None:
        raise SystemExit("the rerun viewer is not installed in this Python environment")
    env = dict(os.environ, XDG_RUNTIME_DIR=str(workdir))
    # The file is given on the command line: ViewerClient.open() loaded it twice here (rows doubled).
    return subprocess.Popen([*cmd, "--headless", "--window-size", size, "--port", str(port), "--hide-welcome-screen",
                             str(rrd)],
                            env=env, stdout=open(workdir / "viewer.log", "w"), stderr=subprocess.STDOUT)


def _connect(port: int, proc: subprocess.Popen, timeout_s: float = 60.0):
    from rerun.experimental import ViewerClient

    t0 = time.monotonic()
    while True:
        try:
            return ViewerClient.connect(f"rerun+http://127.0.0.1:{port}/proxy")
        except Exception:  # noqa: BLE001 - not listening yet
            if proc.poll() is not None or time.monotonic() - t0 > timeout_s:
                raise
            time.sleep(0.3)


def _shot(client, target: Path, width: int, tries: int = 4) -> None:
    """Save a screenshot (software rendering can miss a frame deadline: retry), then shrink it."""
    from PIL import Image

    for k in range(tries):
        try:
            client.save_screenshot(str(target))
            break
        except Exception as exc:  # noqa: BLE001
            if k == tries - 1:
                raise
            print(f"  screenshot attempt {k + 1} failed ({type(exc).__name__}: {exc}); retrying", file=sys.stderr)
    img = Image.open(target).convert("RGB")
    img = img.resize((width, round(img.height * width / img.width)), Image.LANCZOS)
    img.quantize(colors=192, method=Image.Quantize.MEDIANCUT).save(target, optimize=True)
    print(f"wrote {target} ({target.stat().st_size // 1024} kB)")


def _show_tab(client, name: str) -> None:
    """Make the view called ``name`` the active tab of its container (edits the live blueprint)."""
    bp = client.get_blueprint()
    doc = bp.blueprint
    view = next(k for k, v in doc.items() if v.get("ViewBlueprint", {}).get("display_name") == name)
    for v in doc.values():
        c = v.get("ContainerBlueprint")
        if c and view in c.get("contents", []):
            c["active_tab"] = view
    client.set_blueprint(doc, store_id=bp.store_id)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("rrd", nargs="?", type=Path, help="a failed episode's .rrd (default: record the example)")
    p.add_argument("--out", type=Path, default=ROOT / "docs", help="where to write replay_*.png (default docs/)")
    p.add_argument("--size", default="1400x820", help="viewer window size in points")
    p.add_argument("--width", type=int, default=1100, help="width of the written PNGs")
    p.add_argument("--port", type=int, default=9931)
    p.add_argument("--settle", type=float, default=12.0, help="seconds to let the viewer load and paint")
    args = p.parse_args(argv)

    from capmj.replay import read_episode

    work = Path(tempfile.mkdtemp(prefix="capmj-shots-"))
    rrd = args.rrd or record_example(work / "failed-episode.rrd")
    log = read_episode(rrd)
    s = log.summary or {}
    args.out.mkdir(parents=True, exist_ok=True)
    proc = _viewer(args.port, args.size, work, rrd.resolve())
    try:
        client = _connect(args.port, proc)
        time.sleep(args.settle)  # load, first paint (shader compilation on a CPU rasteriser), toasts fade
        _shot(client, args.out / "replay_failure.png", args.width)

        # second view: the attempt document next to the world mid-episode (the block in the cup)
        store = client.get_state().active_recording
        if log.attempts:
            _show_tab(client, "attempt 1")
        mid = [r["start"] + 0.6 * (r["time"] - r["start"]) for r in s.get("primitive_log", [])]
        if mid:
            client.set_time("sim_time", duration=float(mid[-1]), play_state="paused", recording=store)
        time.sleep(args.settle / 2)
        _shot(client, args.out / "replay_attempt.png", args.width)
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
    return 0


if __name__ == "__main__":
    sys.exit(main())
