# Goal: "Stack blocks of the same size in the {c1} zone and {c2} zone respectively."
# "respectively": the big blocks go to the first zone, the small blocks to the second.
words = goal.replace('.', '').split()
zone_colors = [words[i - 1] for i, w in enumerate(words) if w == 'zone']
zones = [[n for n in objects if ' zone ' in n and get_color(n) == c][0] for c in zone_colors]
big = [n for n in objects if ' big ' in n and ' block ' in n]
small = [n for n in objects if ' small ' in n and ' block ' in n]
for group, zone in ((big, zones[0]), (small, zones[1])):
    for block in group:
        put_first_on_second(block, zone)
