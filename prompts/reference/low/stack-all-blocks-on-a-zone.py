# Goal: "Stack all blocks in the {colour} zone": each block on the zone, on top of the ones before.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
words = goal.rstrip('.').split()
zone_color = words[words.index('zone') - 1]
zone = [name for name in objects if f' {zone_color} zone ' in name][0]
blocks = [name for name in objects if ' block ' in name]
for block in blocks:
    put_on(block, zone)
