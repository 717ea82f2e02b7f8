"""Task E: stack-blocks-by-relative-position-and-color."""

from __future__ import annotations

import numpy as np

from capmj.tasks.protocol import Resample, Scene
from capmj.tasks.spawn import Spawner, pick_color, pick_colors

from capmj_tasks.common import SelectedStackTask, start_positions

THRESHOLD = 0.05
MARGIN = 0.01
"""No block's distance may lie within this of the threshold (the selection is unambiguous)."""
MAX_SELECTED = 5
# direction -> (axis, sign): distance = sign * (block - reference) along axis (0 = x, 1 = y).
DIRECTIONS = {"left": (1, -1.0), "right": (1, 1.0), "front": (0, 1.0), "rear": (0, -1.0)}
AXIS_WORD = {0: "front-back", 1: "horizontal"}


def signed_distance(direction: str, pos, ref_pos) -> float:
    """How far (m) ``pos`` lies in ``direction`` of ``ref_pos`` (left = y−, front = x+)."""
    axis, sign = DIRECTIONS[direction]
    return sign * (float(pos[axis]) - float(ref_pos[axis]))


class StackBlocksByRelativePositionAndColor(SelectedStackTask):
    """Stack the blocks lying more than 0.05 m to one side of a reference block.

    Task Description:
        "Stack all the blocks, which are to the {left|right|front|rear} of the {color} block with
        {horizontal|front-back} distance larger than 0.05, in the {zone color} zone."  4–7 small
        blocks of distinct colours and one zone.  Left/right use the horizontal (y) distance,
        front/rear the front-back (x) distance; left = y−, front = x+.

    Randomizations:
        Number of blocks (4–7), colours, zone colour, all poses and yaws; the reference block and
        direction are drawn among those giving 2–5 selected blocks with no block's distance within
        0.01 m of the 0.05 m threshold (else the scene is resampled).  The reference block itself
        is never selected, so ≥ 1 block is always left out.

    Success Conditions:
        The blocks selected from the *initial* positions form one stack inside the zone
        (``predicates.is_stack``) and no other block has its centre in the zone.  Progress =
        (blocks on the valid partial stack + 1 if the zone holds no other block) / (selected + 1).
    """

    name = "stack-blocks-by-relative-position-and-color"

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        sp = Spawner(rng)
        zone = sp.zone(pick_color(rng))
        n = int(rng.integers(4, 8))
        blocks = [sp.block(c, "small") for c in pick_colors(rng, n)]
        names = list(DIRECTIONS)
        for k in rng.permutation(len(blocks) * len(names)):
            ref, direction = blocks[int(k) // len(names)], names[int(k) % len(names)]
            d = {b.obj_id: signed_distance(direction, b.pos, ref.pos) for b in blocks if b is not ref}
            if any(abs(v - THRESHOLD) < MARGIN for v in d.values()):
                continue
            selected = [i for i, v in d.items() if v > THRESHOLD]
            if 2 <= len(selected) <= MAX_SELECTED:
                break
        else:
            raise Resample("no reference block and direction give a clean selection")
        axis = AXIS_WORD[DIRECTIONS[direction][0]]
        goal = (f"Stack all the blocks, which are to the {direction} of the {ref.color} block with {axis} "
                f"distance larger than 0.05, in the {zone.color} zone.")
        return Scene(sp.objects, goal, {
            "zone": zone.obj_id, "reference": ref.obj_id, "direction": direction, "threshold": THRESHOLD,
            "selected": selected, "blocks": [b.obj_id for b in blocks], "start_positions": start_positions(blocks),
        })


TASK = StackBlocksByRelativePositionAndColor()
