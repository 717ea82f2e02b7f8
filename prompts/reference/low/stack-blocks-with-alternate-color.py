# Goal: stack the blocks in the {colour} zone alternating colours, starting with {colour}.
# Written against the low-level API only (--api low): no pick-and-place; the shared helpers
# (_helpers.py, run before it) compose one from guarded moves and the suction.

# --- the plan ----------------------------------------------------------------------------------
words = goal.replace(',', '').rstrip('.').split()
zone_color = words[words.index('zone') - 1]
first_color = words[words.index('color') - 1]
zone = [name for name in objects if f' {zone_color} zone ' in name][0]
blocks = [name for name in objects if ' block ' in name]
first = [name for name in blocks if obj(name)['color'] == first_color]
second = [name for name in blocks if obj(name)['color'] != first_color]
order = []
for k in range(len(blocks)):
    group = first if k % 2 == 0 else second
    if group:
        order.append(group.pop(0))
put_on(order[0], zone)
for lower, upper in zip(order, order[1:]):
    put_on(upper, lower)
