"""The planner API: the only thing LLM-written plan code can touch.

- :mod:`~capmj.agents.api.planner_api` — :class:`PlannerAPI`, the logging facade of one episode
  (names resolved, arguments checked, every call logged); its conventions are stated there;
- :mod:`~capmj.agents.api.interface` — :class:`PlannerInterface`, the facade's public interface
  the functions are written against;
- :mod:`~capmj.agents.api.plan_functions` — :class:`PlanFunctions`, one method per function plan
  code calls (:data:`API_FUNCTIONS`); :mod:`~capmj.agents.api.capravens` the CapRavens-named ones;
- :mod:`~capmj.agents.api.names` (how a written name is read), :mod:`~capmj.agents.api.values`
  (what a position or a pose is, how a value is shown), :mod:`~capmj.agents.api.footprints` (the
  geometry: footprints, surfaces, free positions);
- :mod:`~capmj.agents.api.perceived` — the API over perception (``--perception rgbd``, and
  :func:`~capmj.agents.api.perceived.make_api` for any mode) with
  :mod:`~capmj.agents.api.perception_audit`; imported from its module, since it loads the
  perception stack.
"""

from capmj.agents.api.footprints import Footprints
from capmj.agents.api.interface import PlannerInterface
from capmj.agents.api.plan_functions import API_FUNCTIONS, PlanFunctions
from capmj.agents.api.planner_api import PlannerAPI

__all__ = ["API_FUNCTIONS", "Footprints", "PlanFunctions", "PlannerAPI", "PlannerInterface"]
