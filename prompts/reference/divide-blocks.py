# Goal: "Divide the blocks into groups of {k} and stack each group (also including the group with
# block number less than {k}) in a different zone."
# Cut the blocks into groups of k (the last group takes whatever is left) and stack each group in
# a zone of its own.
k = int(goal.split('groups of ')[1].split()[0])
zones = [name for name in objects if ' zone ' in name]
blocks = [name for name in objects if ' block ' in name]
groups = [blocks[i:i + k] for i in range(0, len(blocks), k)]
if len(groups) > len(zones):
    say(f'{len(groups)} groups but only {len(zones)} zones')
for group, zone in zip(groups, zones):
    stack_objects_in_order(group, zone)
