# Goal: "Construct a circle with suitable radius with alternating {c1} and {c2} blocks in the zone."
# All blocks of the two colours evenly on a circle around the zone centre, colours alternating,
# each block turned to face the centre.  Two radially turned neighbours take
# size/2 * (cos a + sin a) of the chord each (a = pi / n), so this radius leaves a 1 cm gap.
words = goal.rstrip('.').split()
c1, c2 = words[words.index('alternating') + 1], words[words.index('alternating') + 3]
zone = [name for name in objects if ' zone ' in name][0]
first = [name for name in objects if ' block ' in name and get_color(name) == c1]
second = [name for name in objects if ' block ' in name and get_color(name) == c2]
n = len(first) + len(second)
bbox = get_bbox(first[0])
size = bbox[5] - bbox[2]
a = math.pi / n
radius = max(size, (size * (math.cos(a) + math.sin(a)) + 0.01) / (2 * math.sin(a)))
cx, cy, _ = get_obj_pos(zone)
for k in range(n):
    block = first.pop(0) if k % 2 == 0 else second.pop(0)
    angle = 2 * math.pi * k / n
    pos = [cx + radius * math.cos(angle), cy + radius * math.sin(angle), size / 2]
    put_first_on_second(block, (pos, [0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2)]))
