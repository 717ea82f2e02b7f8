# Goal: "Stack all the blocks, which are to the {left|right|front|rear} of the {color} block with
# {horizontal|front-back} distance larger than 0.05, in the {zone color} zone."
# World axes: left = -y, right = +y, front = +x, rear = -x.  The selection is made from the
# positions before anything moves.
words = goal.replace(',', '').rstrip('.').split()
direction = words[words.index('of') - 1]
ref_color = words[words.index('block') - 1]
threshold = float(words[words.index('than') + 1])
zone_color = words[words.index('zone') - 1]
axis, sign = {'left': (1, -1), 'right': (1, 1), 'front': (0, 1), 'rear': (0, -1)}[direction]

blocks = [name for name in objects if ' block ' in name]
reference = [name for name in blocks if get_color(name) == ref_color][0]
zone = [name for name in objects if f' {zone_color} zone ' in name][0]
ref_pos = get_obj_pos(reference)
selected = [name for name in blocks
            if name != reference and sign * (get_obj_pos(name)[axis] - ref_pos[axis]) > threshold]
for block in selected:
    put_first_on_second(block, zone)
