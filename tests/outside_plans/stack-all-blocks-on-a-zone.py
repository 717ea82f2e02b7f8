# Goal: "Stack all blocks in the {color} zone."
# Putting a block on a zone puts it on what is already stacked there, so one call per block.
color = goal.split(' zone')[0].split()[-1]
zone = [n for n in objects if ' zone ' in n and get_color(n) == color][0]
blocks = [n for n in objects if ' block ' in n]
for block in blocks:
    put_first_on_second(block, zone)
