"""Write run folders with today's capmj: an oracle run and a scripted-LLM run (stub server)."""
import sys, os, itertools
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from capmj.bench.cli import main
from llm_stub_server import StubLLMServer
from test_llm_chain import OBJ_NAMES, REPORTER, RIGHT_PLAN, TASK, Router, code, parse_function_answer
import test_trust as T

out = Path(sys.argv[1])
assert main(["--agent", "oracle", "--tasks", TASK, "--seeds", "10001,10003", "--workers", "0", "--no-log",
             "--no-progress", "--out", str(out / "oracle")]) == 0
answers = itertools.cycle([
    "I cannot help with that.", T.CHEAP["motion"],                       # 10001: no_code, then motion
    T.CHEAP["sandbox_violation"], T.CHEAP["unknown_object"],           # 10003: sandbox, then unknown object
    code(RIGHT_PLAN),                                                  # 10005: success
    T.CHEAP["syntax"], T.CHEAP["api_misuse"],                          # 10007: syntax, then api misuse
])
def planner(request):
    return next(answers)
with StubLLMServer() as s:
    s.respond_with(Router(planner=planner, parse_obj_name=code(OBJ_NAMES), parse_function=parse_function_answer,
                          parse_completion=code(REPORTER)))
    os.environ["CAPMJ_LLM_CACHE"] = str(out / "cache")
    rc = main(["--agent", "llm", "--model", "openai/stub", "--api-base", s.base_url, "--tasks", TASK,
               "--seeds", "10001,10003,10005,10007", "--attempts", "2", "--reporter", "text", "--workers", "0",
               "--concurrency", "1", "--no-log", "--no-progress", "--out", str(out / "llm")])
    print("llm rc", rc)
