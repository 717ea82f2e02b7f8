# Goal: stack the blocks of the colour with the most blocks in the zone.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
zone = [name for name in objects if ' zone ' in name][0]
blocks = [name for name in objects if ' block ' in name]
counts = {}
for block in blocks:
    counts[obj(block)['color']] = counts.get(obj(block)['color'], 0) + 1
top = max(counts, key=lambda colour: counts[colour])
order = [block for block in blocks if obj(block)['color'] == top]
put_on(order[0], zone)
for lower, upper in zip(order, order[1:]):
    put_on(upper, lower)
