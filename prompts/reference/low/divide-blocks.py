# Goal: "Divide the blocks into groups of {k} and stack each group in a zone": consecutive groups
# of k blocks, each stacked on its own zone.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
k = int(goal.split('groups of ')[1].split()[0])
zones = [name for name in objects if ' zone ' in name]
blocks = [name for name in objects if ' block ' in name]
groups = [blocks[i:i + k] for i in range(0, len(blocks), k)]
if len(groups) > len(zones):
    say(f'{len(groups)} groups but only {len(zones)} zones')
for group, zone in zip(groups, zones):
    put_on(group[0], zone)
    for lower, upper in zip(group, group[1:]):
        put_on(upper, lower)
