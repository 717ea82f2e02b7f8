"""Task D: stack-blocks-by-color-and-size."""

from __future__ import annotations

import numpy as np

from capmj.tasks.protocol import Scene
from capmj.tasks.spawn import COOL_COLORS, WARM_COLORS, Spawner, pick_color

from capmj_tasks.common import SelectedStackTask, shuffled

SIZE_WORD = {"big": "bigger", "small": "smaller"}
MAX_SELECTED = {"big": 4, "small": 5}
"""Stack height cap: 4 big (0.24 m) or 5 small (0.20 m) blocks stay inside z ≤ 0.3."""


class StackBlocksByColorAndSize(SelectedStackTask):
    """Stack only the blocks of one size and one colour temperature in the zone.

    Task Description:
        "Stack only the {bigger|smaller} blocks of {warm|cool} color in the {color} zone."  One
        zone and 4–7 blocks of both sizes, coloured from the warm (red, yellow, orange, brown,
        pink) and cool (blue, green, cyan, purple, gray) palette names.

    Randomizations:
        Size and temperature words, number of blocks (4–7), number selected (2 … min(n − 1, 4
        big / 5 small)), colours (may repeat), sizes of the others (at least one block of the
        other size), zone colour, spawn order, all poses and yaws.  The selection therefore always
        has ≥ 2 blocks and leaves ≥ 1 block out (defect 1 of the original fixed).

    Success Conditions:
        The selected blocks form one stack inside the zone (``predicates.is_stack``) and no other
        block has its centre in the zone.  Progress = (blocks on the valid partial stack + 1 if
        the zone holds no other block) / (selected + 1).
    """

    name = "stack-blocks-by-color-and-size"

    def sample_scene(self, rng: np.random.Generator) -> Scene:
        size = ("big", "small")[int(rng.integers(0, 2))]
        temp = ("warm", "cool")[int(rng.integers(0, 2))]
        sel_pool = WARM_COLORS if temp == "warm" else COOL_COLORS
        all_pool = WARM_COLORS + COOL_COLORS
        other_size = "small" if size == "big" else "big"
        n = int(rng.integers(4, 8))
        n_sel = int(rng.integers(2, min(n - 1, MAX_SELECTED[size]) + 1))
        attrs = [(size, pick_color(rng, sel_pool)) for _ in range(n_sel)]
        attrs.append((other_size, pick_color(rng, all_pool)))
        while len(attrs) < n:
            s = ("big", "small")[int(rng.integers(0, 2))]
            c = pick_color(rng, all_pool)
            if s == size and c in sel_pool:
                continue
            attrs.append((s, c))
        sp = Spawner(rng)
        zone = sp.zone(pick_color(rng))
        blocks = [sp.block(c, s) for s, c in shuffled(rng, attrs)]
        selected = [b.obj_id for b in blocks if b.size == size and b.color in sel_pool]
        return Scene(
            sp.objects,
            f"Stack only the {SIZE_WORD[size]} blocks of {temp} color in the {zone.color} zone.",
            {"zone": zone.obj_id, "size": size, "temperature": temp, "selected": selected,
             "blocks": [b.obj_id for b in blocks]},
        )


TASK = StackBlocksByColorAndSize()
