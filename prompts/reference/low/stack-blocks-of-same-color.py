# Goal: stack the blocks of each zone's colour in that zone.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
zones = [name for name in objects if ' zone ' in name]
blocks = [name for name in objects if ' block ' in name]
for zone in zones:
    color = obj(zone)['color']
    for block in blocks:
        if obj(block)['color'] == color:
            put_on(block, zone)
