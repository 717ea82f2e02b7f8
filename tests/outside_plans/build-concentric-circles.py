# Goal: "Construct two concentric circles in the zone using {n} {c1} and {n+4} {c2} blocks."
# Inner circle: the n c1 blocks; outer circle: the n+4 c2 blocks; both centred on the zone, radii
# chosen so neighbours on a circle are >= 6.5 cm apart and the circles >= 6 cm apart.
words = goal.replace('.', '').split()
i = words.index('using')
c1, c2 = words[i + 2], words[i + 5]
zone = [n for n in objects if ' zone ' in n][0]
inner = [b for b in objects if ' block ' in b and get_color(b) == c1]
outer = [b for b in objects if ' block ' in b and get_color(b) == c2]
cx, cy, _ = get_obj_pos(zone)
r1 = max(0.06, 0.065 / (2 * math.sin(math.pi / len(inner))))
r2 = max(r1 + 0.06, 0.065 / (2 * math.sin(math.pi / len(outer))))
def ring(r, k):
    return [[cx + r * math.cos(2 * math.pi * j / k), cy + r * math.sin(2 * math.pi * j / k)] for j in range(k)]
points = ring(r1, len(inner)) + ring(r2, len(outer))
for p in points:
    for name in is_target_occupied(p, 0.03):
        if ' block ' in name:
            put_first_on_second(name, get_random_free_pos(targ=points + [zone]))
for block, p in zip(inner + outer, points):
    put_first_on_second(block, p)
