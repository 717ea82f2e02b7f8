# A robot arm will pick and place objects on a table to reach a goal. Write the check of the goal:
# one call for each thing the goal requires. capmj measures every call on the scene after the robot
# acted; the goal is achieved when no call fails.
#
# Pick objects and places (each object is a dict with "name", "kind", "color", "size"):
#   blocks(color=None, size=None, start_area=None)  the blocks; color: a colour, a list of colours, "warm" or "cool";
#                                                   size: "big" or "small"; start_area: the quarter they started in
#   other_blocks(objs)                              every block not in objs
#   blocks_beside(block, side, more_than=0.0)       the blocks that started more than that far (m) to the side of block
#                                                   ("left", "right", "front", "rear")
#   zone(color=None), bowl(color=None), ball()      the zone / bowl of that colour (no colour: the only one)
#   zones(), bowls()                                every zone / bowl; each has a "color"
# Places: a zone, a bowl, a quarter of the table ("top left", "top right", "bottom left", "bottom right"),
# or a list of places (in any one of them, e.g. bowls()).
#
# The checks (objs: a list of objects or one object):
#   require_inside(objs, place)          every one of objs is in the place
#   require_outside(objs, place)         none of objs is in the place
#   require_stack(objs, place=None)      objs form one upright tower, one on top of the other (in the place):
#                                        a single column; a structure with several blocks in a layer is require_layers
#   require_layers(objs, [n1, n2, ...])  n1 of objs on the table, n2 on top of them, ... and nothing higher
#   require_on_table(objs)               every one of objs stands upright on the table, not on another block
#   require_unmoved(objs)                objs are still where they started
#   require_circle(objs, around=None)    their centres lie on one circle (centred on the object `around`)
#   require_row(objs)                    their centres lie on one straight line
#   require_alternating(objs, first_color=None)  neighbours differ in colour (a tower from the bottom, with
#                                                first_color at the bottom; else around their centre)
#   require_count(objs, place, n)        exactly n of objs are in the place
#   require_different_colors(objs)       no two of objs have the same colour
# Write only these calls, loops and plain Python; do not set judge, do not import anything.

#@ stop: ["\n\n# goal:", "\nobjects = [", "\n    {'name': "]

# goal: Put every block in one of the bowls.
require_inside(blocks(), bowls())

# goal: Move all blocks into the gray zone.
require_inside(blocks(), zone("gray"))

# goal: Stack the red and the blue blocks in the white zone.
require_stack(blocks(color=["red", "blue"]), zone("white"))

# goal: Stack only the small blocks in the purple zone and leave the big blocks where they are.
small = blocks(size="small")
require_stack(small, zone("purple"))
require_outside(other_blocks(small), zone("purple"))
require_unmoved(blocks(size="big"))

# goal: Put the blocks of each colour in the zone of that colour, every block on the table.
for z in zones():
    require_inside(blocks(color=z["color"]), z)
require_on_table(blocks())

# goal: Move the cool blocks from the bottom left area to the top right area.
require_inside(blocks(color="cool", start_area="bottom left"), "top right")

# goal: Build a wall in the zone: three blocks on the table and two blocks on top of them.
require_inside(blocks(), zone())
require_layers(blocks(), [3, 2])

# goal: Arrange the pink and cyan blocks on the table in a ring around the ball, pink and cyan in turn.
ring = blocks(color=["pink", "cyan"])
require_on_table(ring)
require_circle(ring, around=ball())
require_alternating(ring)

# goal: Put two of the red blocks in the blue bowl and no other block.
reds = blocks(color="red")
require_count(reds, bowl("blue"), 2)
require_outside(other_blocks(reds), bowl("blue"))

# goal: Put the blocks of the colour that has the fewest blocks in the bowl.
colors = [b["color"] for b in blocks()]
fewest = min(colors, key=colors.count)
require_inside(blocks(color=fewest), bowl())

# goal: Stack the blocks that are more than 0.1 to the rear of the white block on top of it.
white = blocks(color="white")
require_stack(white + blocks_beside(white[0], "rear", 0.1))

<<QUESTION>>
