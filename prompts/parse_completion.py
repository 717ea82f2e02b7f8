import numpy as np, math
from env_utils import get_obj_names, get_obj_pos, get_obj_rot, get_bbox, get_obj_pos_dict, get_color, is_target_occupied

# Judge whether the goal in the last comment is achieved in the current scene. Set judge = True or False, reason = a short explanation and wrong = [names of the objects whose state is wrong].
# Already defined for you (do not redefine them):
#   poses = {name: ([x, y, z], [roll, pitch, yaw])} of every object (metres, radians); sizes = {block name: edge length}
#   blocks, zones, bowls = lists of object names; goal_objects = {'green zone': name, ...} for each object the goal names,
#   also as variables: green_zone = 'fixed green zone with obj_id 1'
#   size(name) -> edge length of a block; upright(name) -> not tilted; in_zone(obj, zone), in_bowl(obj, bowl), on_top(upper, lower) -> bool
# get_obj_pos(name) -> [x, y, z]. get_color(name) -> 'blue'.
# Table: x from 0.25 (top) to 0.75 (bottom), y from -0.5 (left) to 0.5 (right), z up, table top z = 0. Blocks: tiny 0.02 m, small 0.04 m, big 0.06 m cubes.
# In a zone: the centre lies inside the zone's square (0.12 m unless scaled, turned with the zone; in_zone checks it). In a bowl: the centre lies within 0.05 of the bowl centre in x-y.
# A stack: centres within 0.02 of each other in x-y, the lowest on the table (or zone), each block resting on the one below
# (z difference = mean of the two block sizes, +-0.015), none tilted.
# Rules: no imports; only these names, np and math.

#@ stop: ["\n\nobjects = ["]

#@ example: stack_done
#@ scene: {"objects": [["zone", "green", 0.5, 0.2], ["zone", "red", 0.62, -0.25], ["block", "blue", 0.5, 0.2, "small", 0.02], ["block", "yellow", 0.5, 0.2, "small", 0.06], ["block", "red", 0.5, 0.2, "small", 0.1]]}
#@ expect: true
#@ check: wrong == []
objects = ['fixed green zone with obj_id 1', 'fixed red zone with obj_id 2', 'movable small blue block with obj_id 3', 'movable small yellow block with obj_id 4', 'movable small red block with obj_id 5']
# goal: Stack all blocks in the green zone.
poses = get_obj_pos_dict()
tower = sorted(blocks, key=lambda name: poses[name][0][2])
outside = [name for name in tower if not in_zone(name, green_zone)]
loose = [upper for lower, upper in zip(tower, tower[1:]) if not on_top(upper, lower)]
tilted = [name for name in tower if not upright(name)]
on_table = abs(poses[tower[0]][0][2] - size(tower[0]) / 2) < 0.015
judge = on_table and not outside and not loose and not tilted
reason = f'{len(tower) - len(outside)} of {len(tower)} blocks in the green zone; not resting on the block below: {loose}'
wrong = outside + loose + tilted
#@ end

#@ example: stack_not_done
#@ scene: {"objects": [["zone", "orange", 0.45, -0.2], ["block", "cyan", 0.45, -0.2, "small", 0.02], ["block", "pink", 0.6, 0.15], ["zone", "blue", 0.4, 0.3]]}
#@ expect: false
#@ check: wrong == ['movable small pink block with obj_id 3']
objects = ['fixed orange zone with obj_id 1', 'movable small cyan block with obj_id 2', 'movable small pink block with obj_id 3', 'fixed blue zone with obj_id 4']
# goal: Stack all blocks in the orange zone.
blocks = [name for name in objects if ' block ' in name]
tower = sorted(blocks, key=lambda name: poses[name][0][2])
outside = [name for name in tower if not in_zone(name, orange_zone)]
loose = [upper for lower, upper in zip(tower, tower[1:]) if not on_top(upper, lower) and upper not in outside]
judge = not outside and not loose
reason = f'outside the orange zone: {outside}; not resting on the block below: {loose}'
wrong = outside + loose
#@ end

#@ example: block_in_bowl
#@ scene: {"objects": [["bowl", "blue", 0.5, -0.1], ["block", "red", 0.5, -0.1, "small", 0.024], ["bowl", "red", 0.4, 0.25], ["block", "green", 0.62, 0.2]]}
#@ expect: true
#@ check: wrong == []
objects = ['fixed blue bowl with obj_id 1', 'movable small red block with obj_id 2', 'fixed red bowl with obj_id 3', 'movable small green block with obj_id 4']
# goal: Put the red block in the blue bowl.
poses = get_obj_pos_dict()
(x, y, _), (bx, by, _) = poses[red_block][0], poses[blue_bowl][0]
judge = in_bowl(red_block, blue_bowl)
reason = f'the red block is {math.hypot(x - bx, y - by):.3f} m from the blue bowl centre'
wrong = [] if judge else [red_block]
#@ end

#@ example: row_wrong_order
#@ scene: {"objects": [["block", "red", 0.65, 0.1], ["block", "green", 0.65, 0.0], ["block", "blue", 0.65, -0.1]]}
#@ expect: false
#@ check: sorted(wrong) == ['movable small blue block with obj_id 3', 'movable small red block with obj_id 1']
objects = ['movable small red block with obj_id 1', 'movable small green block with obj_id 2', 'movable small blue block with obj_id 3']
# goal: Line the blocks up along the bottom side from left to right: red, green, blue, 0.1 m apart.
# Left to right is increasing y; the bottom side has large x.
poses = get_obj_pos_dict()
by_color = {get_color(name): name for name in blocks}
order = [by_color[color] for color in ['red', 'green', 'blue']]
ys = [poses[name][0][1] for name in order]
targets = [ys[1] - 0.1, ys[1], ys[1] + 0.1]
wrong = [name for name, y, t in zip(order, ys, targets) if abs(y - t) > 0.02 or poses[name][0][0] < 0.6]
judge = not wrong
reason = f'y of red, green, blue: {np.round(ys, 3).tolist()}, wanted about {np.round(targets, 3).tolist()}'
#@ end

<<QUESTION>>
