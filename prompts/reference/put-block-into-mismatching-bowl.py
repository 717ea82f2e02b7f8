# Goal: "Put the blocks in the bowls with mismatching colors."
# Every block goes into a bowl of another colour, one block per bowl: try the bowl orders until
# every block gets a differently coloured bowl of its own.
bowls = [name for name in objects if ' bowl ' in name]
blocks = [name for name in objects if ' block ' in name]
assignment = None
for chosen in itertools.permutations(bowls, len(blocks)):
    if all(get_color(block) != get_color(bowl) for block, bowl in zip(blocks, chosen)):
        assignment = list(zip(blocks, chosen))
        break
if assignment is None:
    say('no bowl assignment with mismatching colours exists')
else:
    for block, bowl in assignment:
        put_first_on_second(block, bowl)
