import numpy as np, math, itertools
from shapely.geometry import Point, Polygon, LineString, box
from env_utils import get_obj_names, get_obj_pos, get_obj_rot, get_bbox, get_color, get_obj_positions_np, is_target_occupied, get_random_free_pos, put_first_on_second, stack_objects_in_order, denormalize, get_corner_name, get_side_name, say
from plan_utils import parse_obj_name, parse_position

# A UR5e robot with a suction cup picks and places objects on a table. Write the plan for the goal in the last comment.
# API (metres, radians, quaternions (x, y, z, w)); names look like 'movable small blue block with obj_id 3', 'fixed red zone with obj_id 1':
# get_obj_names() -> names of all objects; the list `objects` holds them too.
# get_obj_pos(name) -> [x, y, z] of the object's centre (a fixture: the origin of its local frame, the centre of its slot (0, 0, 0)). get_color(name) -> 'blue'.
# get_obj_rot(name) -> quaternion. Objects start at random yaws; yaw = 2 * math.atan2(q[2], q[3]).
# get_bbox(name) -> (xmin, ymin, zmin, xmax, ymax, zmax), world axis-aligned: a square zone of side s turned by yaw t spans s * (abs(cos(t)) + abs(sin(t))). get_obj_positions_np(names) -> (n, 3) array.
# is_target_occupied(name) -> names of objects overlapping that object (e.g. blocks in a zone); is_target_occupied([x, y], r) -> objects within r of the point.
# get_random_free_pos(targ=None, area=(xmin, ymin, xmax, ymax)) -> a free [x, y, 0] in the area, away from every object and from targ.
# put_first_on_second(name, target): pick the object, place it on target: a name (on its top, turned like the block or zone it goes on; a zone: on whatever is already stacked in it; a bowl: inside),
#   [x, y] or [x, y, z] (resting on what is there, aligned with the world axes; z = height of the object's centre when let go, never below resting), or ([x, y(, z)], quaternion) (turned to its yaw).
# stack_objects_in_order(names, targ=None): names[0] at the bottom (on targ if given), each next one on the previous one.
# denormalize([u, v]) -> [x, y] for u = 0 (left) .. 1 (right), v = 0 (bottom) .. 1 (top). get_corner_name(pos), get_side_name(pos) -> 'top left corner', 'left side'.
# say(message) logs a message.
# parse_obj_name(description, f'objects = {get_obj_names()}') -> the names matching a description (another program answers it).
# parse_position(description) -> a position [x, y(, z)] or a list of positions for a description.
# Table: x from 0.25 (top/rear) to 0.75 (bottom/front), y from -0.5 (left) to 0.5 (right), z up, table top z = 0, robot base at (0, 0).
# Halves: top x < 0.5, bottom x > 0.5, left y < 0, right y > 0. Blocks: tiny 0.02 m, small 0.04 m, big 0.06 m cubes. Zones: flat squares, 0.12 m unless scaled up. Bowls: 0.12 m wide.
# Warm colours: red, yellow, orange, brown, pink, gold. Cool colours: blue, green, cyan, purple, gray, violet, indigo, silver.
# Fixed objects (zones, bowls, balls, fixtures) cannot be picked; neither can an object with something on top of it.
# Rules: no imports and no classes; only the functions above, np, math, itertools and shapely. Write the whole plan at once, with comments on your reasoning.
# You may call a clearly named helper function that does not exist yet: it will be written for you.

#@ stop: ["\n\nobjects = ["]

#@ example: stack_in_zone
#@ scene: {"objects": [["zone", "green", 0.45, 0.25], ["zone", "red", 0.62, -0.3], ["block", "blue", 0.4, -0.15], ["block", "yellow", 0.6, 0.05], ["block", "red", 0.33, 0.05]]}
#@ task: stack-all-blocks-on-a-zone
#@ info: {"zone": 1, "distractor_zones": [2], "blocks": [3, 4, 5]}
objects = ['fixed green zone with obj_id 1', 'fixed red zone with obj_id 2', 'movable small blue block with obj_id 3', 'movable small yellow block with obj_id 4', 'movable small red block with obj_id 5']
# Stack all blocks in the green zone.
# Putting a block on a zone puts it on top of what is already stacked there, so one call per block builds the stack.
zone = 'fixed green zone with obj_id 1'
blocks = [name for name in objects if ' block ' in name]
for block in blocks:
    put_first_on_second(block, zone)
#@ end

#@ example: on_block_and_corner
#@ scene: {"objects": [["block", "blue", 0.55, -0.2], ["block", "yellow", 0.4, 0.1], ["block", "red", 0.6, 0.25]]}
#@ check: np.hypot(get_obj_pos(2)[0] - get_obj_pos(1)[0], get_obj_pos(2)[1] - get_obj_pos(1)[1]) < 0.02 and get_obj_pos(2)[2] > 0.05
#@ check: np.hypot(get_obj_pos(3)[0] - 0.3, get_obj_pos(3)[1] - 0.4) < 0.02
objects = ['movable small blue block with obj_id 1', 'movable small yellow block with obj_id 2', 'movable small red block with obj_id 3']
# Put the yellow block on the blue block, then move the red block to the top right corner.
put_first_on_second('movable small yellow block with obj_id 2', 'movable small blue block with obj_id 1')
corner = parse_position('the top right corner')
put_first_on_second('movable small red block with obj_id 3', corner)
#@ end

#@ example: left_of_bowl_into_bowl
#@ scene: {"objects": [["bowl", "green", 0.5, 0.0], ["block", "red", 0.4, -0.25], ["block", "blue", 0.62, -0.15], ["block", "yellow", 0.42, 0.22], ["bowl", "purple", 0.62, 0.3]]}
#@ check: all(np.hypot(get_obj_pos(i)[0] - 0.5, get_obj_pos(i)[1]) < 0.05 for i in (2, 3))
#@ check: np.hypot(get_obj_pos(4)[0] - 0.42, get_obj_pos(4)[1] - 0.22) < 0.01
objects = ['fixed green bowl with obj_id 1', 'movable small red block with obj_id 2', 'movable small blue block with obj_id 3', 'movable small yellow block with obj_id 4', 'fixed purple bowl with obj_id 5']
# Put the blocks that are left of the green bowl into it.
# Left means smaller y; parse_obj_name finds the names.
bowl = 'fixed green bowl with obj_id 1'
blocks = parse_obj_name('the blocks left of the green bowl', f'objects = {get_obj_names()}')
for block in blocks:
    put_first_on_second(block, bowl)
#@ end

#@ example: only_block_in_zone
#@ scene: {"objects": [["zone", "blue", 0.5, 0.2], ["block", "green", 0.5, 0.2], ["block", "red", 0.4, -0.2], ["zone", "yellow", 0.62, -0.25]]}
#@ check: is_target_occupied(1) == ['movable small red block with obj_id 3']
objects = ['fixed blue zone with obj_id 1', 'movable small green block with obj_id 2', 'movable small red block with obj_id 3', 'fixed yellow zone with obj_id 4']
# Make the red block the only block in the blue zone.
# First clear the zone: move every other block in it to a free spot, highest first (a block under another cannot be picked).
zone = 'fixed blue zone with obj_id 1'
red_block = 'movable small red block with obj_id 3'
others = [name for name in is_target_occupied(zone) if ' block ' in name and name != red_block]
for name in sorted(others, key=lambda n: get_obj_pos(n)[2], reverse=True):
    put_first_on_second(name, get_random_free_pos(targ=zone))
put_first_on_second(red_block, zone)
#@ end

#@ example: unstack_tower
#@ scene: {"objects": [["block", "red", 0.55, 0.1, "small", 0.02], ["block", "green", 0.55, 0.1, "small", 0.06], ["block", "blue", 0.55, 0.1, "small", 0.1]]}
#@ check: all(get_obj_pos(i)[0] < 0.5 and get_obj_pos(i)[2] < 0.03 for i in (1, 2, 3))
objects = ['movable small red block with obj_id 1', 'movable small green block with obj_id 2', 'movable small blue block with obj_id 3']
# Take the tower apart and put every block on the table in the top half.
# Top half: x < 0.5. Move the highest block first.
blocks = [name for name in objects if ' block ' in name]
for block in sorted(blocks, key=lambda name: get_obj_pos(name)[2], reverse=True):
    put_first_on_second(block, get_random_free_pos(area=(0.25, -0.5, 0.5, 0.5)))
#@ end

#@ example: row_by_color
#@ scene: {"objects": [["block", "blue", 0.35, -0.2], ["block", "red", 0.4, 0.3], ["block", "green", 0.3, 0.05]]}
#@ check: all(np.hypot(get_obj_pos(i)[0] - 0.65, get_obj_pos(i)[1] - y) < 0.015 for i, y in ((2, -0.1), (3, 0.0), (1, 0.1)))
objects = ['movable small blue block with obj_id 1', 'movable small red block with obj_id 2', 'movable small green block with obj_id 3']
# Line the blocks up along the bottom side from left to right: red, green, blue, 0.1 m apart.
# Bottom side: large x. Left to right: increasing y. Centre the row at y = 0.
order = ['red', 'green', 'blue']
for i, color in enumerate(order):
    block = [name for name in objects if ' block ' in name and get_color(name) == color][0]
    put_first_on_second(block, [0.65, (i - (len(order) - 1) / 2) * 0.1])
#@ end

#@ example: stack_by_distance
#@ scene: {"objects": [["zone", "pink", 0.6, 0.25], ["block", "blue", 0.35, -0.1], ["block", "orange", 0.6, -0.2], ["block", "cyan", 0.45, 0.3]]}
#@ task: stack-all-blocks-on-a-zone
#@ info: {"zone": 1, "distractor_zones": [], "blocks": [2, 3, 4]}
#@ check: get_obj_pos(2)[2] < get_obj_pos(4)[2] < get_obj_pos(3)[2]
objects = ['fixed pink zone with obj_id 1', 'movable small blue block with obj_id 2', 'movable small orange block with obj_id 3', 'movable small cyan block with obj_id 4']
# Stack the blocks in the pink zone ordered by their distance to the robot, nearest at the bottom.
# The robot base is at (0, 0); distances are measured in the xy plane.
def distance_to_robot(name):
    x, y, _ = get_obj_pos(name)
    return math.hypot(x, y)

blocks = sorted([name for name in objects if ' block ' in name], key=distance_to_robot)
stack_objects_in_order(blocks, 'fixed pink zone with obj_id 1')
#@ end

<<QUESTION>>
