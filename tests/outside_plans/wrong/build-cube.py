# WRONG PLAN (kept as a negative case): leaves 2 cm gaps between the blocks "to be safe"; a 2*2*2
# cube of 4 cm blocks at a 6 cm pitch has holes in it, not a cube (the judge wants neighbours at
# most 5 cm apart, centre to centre).
zone = [n for n in objects if ' zone ' in n][0]
blocks = [n for n in objects if ' block ' in n]
cx, cy, _ = get_obj_pos(zone)
pitch = 0.06
cells = [(cx + dx * pitch / 2, cy + dy * pitch / 2) for dx in (-1, 1) for dy in (-1, 1)]
for i, block in enumerate(blocks[:8]):
    x, y = cells[i % 4]
    put_first_on_second(block, [x, y])
