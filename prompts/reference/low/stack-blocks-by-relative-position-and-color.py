# Goal: stack the blocks more than {d} m {left/right/front/rear} of the {colour} block in the
# {colour} zone (left = y-, right = y+, front = x+, rear = x-).
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
words = goal.replace(',', '').rstrip('.').split()
direction = words[words.index('of') - 1]
ref_color = words[words.index('block') - 1]
threshold = float(words[words.index('than') + 1])
zone_color = words[words.index('zone') - 1]
axis, sign = {'left': (1, -1), 'right': (1, 1), 'front': (0, 1), 'rear': (0, -1)}[direction]

blocks = [name for name in objects if ' block ' in name]
reference = [name for name in blocks if obj(name)['color'] == ref_color][0]
zone = [name for name in objects if f' {zone_color} zone ' in name][0]
ref_pos = obj(reference)['position']
selected = [name for name in blocks
            if name != reference and sign * (obj(name)['position'][axis] - ref_pos[axis]) > threshold]
for block in selected:
    put_on(block, zone)
