# Goal: "Put the blocks in the bowls with mismatching colors."
# Give every block its own bowl of another colour when there are enough bowls.
bowls = [n for n in objects if ' bowl ' in n]
blocks = [n for n in objects if ' block ' in n]
assignment = None
for perm in itertools.permutations(bowls, min(len(blocks), len(bowls))):
    if all(get_color(bl) != get_color(bw) for bl, bw in zip(blocks, perm)):
        assignment = list(zip(blocks, perm))
        break
if assignment is None:  # fewer bowls than blocks: any other-coloured bowl
    assignment = [(bl, [bw for bw in bowls if get_color(bw) != get_color(bl)][0]) for bl in blocks]
for block, bowl in assignment:
    put_first_on_second(block, bowl)
