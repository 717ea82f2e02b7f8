# Goal: stack the bigger/smaller blocks of warm/cool colours in the {colour} zone.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
warm_colors = ['red', 'yellow', 'orange', 'brown', 'pink', 'gold']
cool_colors = ['blue', 'green', 'cyan', 'purple', 'gray', 'violet', 'indigo', 'silver']
words = goal.rstrip('.').split()
size = 'big' if 'bigger' in words else 'small'
palette = warm_colors if 'warm' in words else cool_colors
zone_color = words[words.index('zone') - 1]
zone = [name for name in objects if f' {zone_color} zone ' in name][0]
selected = [name for name in objects
            if ' block ' in name and f' {size} ' in name and obj(name)['color'] in palette]
for block in selected:
    put_on(block, zone)
