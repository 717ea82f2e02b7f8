# Goal: put each block into the bowl of its colour.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
bowls = [name for name in objects if ' bowl ' in name]
blocks = [name for name in objects if ' block ' in name]
for block in blocks:
    matching = [bowl for bowl in bowls if obj(bowl)['color'] == obj(block)['color']]
    if matching:
        put_on(block, matching[0])
