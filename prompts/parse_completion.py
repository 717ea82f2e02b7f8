import numpy as np, math
from env_utils import get_obj_names, get_obj_pos, get_obj_rot, get_bbox, get_obj_pos_dict, get_color, is_target_occupied

# Judge whether the goal in the last comment is achieved in the current scene. Set judge = True or False and reason = a short explanation.
# get_obj_pos_dict() -> {name: ([x, y, z], [roll, pitch, yaw])} (metres, radians). get_obj_pos(name) -> [x, y, z]. get_color(name) -> 'blue'.
# Table: x from 0.25 (top) to 0.75 (bottom), y from -0.5 (left) to 0.5 (right), z up, table top z = 0. Blocks: tiny 0.02 m, small 0.04 m, big 0.06 m cubes.
# In a zone: the centre's x and y lie within 0.06 of the zone centre (0.12 m square). In a bowl: the centre lies within 0.05 of the bowl centre in x-y.
# A stack: centres within 0.02 of each other in x-y, the lowest on the table (or zone), each block resting on the one below
# (z difference = mean of the two block sizes, +-0.015), none tilted (|roll| and |pitch| below 0.26 modulo pi/2).
# Rules: no imports; only these functions, np and math.

#@ example: stack_done
#@ scene: {"objects": [["zone", "green", 0.5, 0.2], ["zone", "red", 0.62, -0.25], ["block", "blue", 0.5, 0.2, "small", 0.02], ["block", "yellow", 0.5, 0.2, "small", 0.06], ["block", "red", 0.5, 0.2, "small", 0.1]]}
#@ expect: true
objects = ['fixed green zone with obj_id 1', 'fixed red zone with obj_id 2', 'movable small blue block with obj_id 3', 'movable small yellow block with obj_id 4', 'movable small red block with obj_id 5']
# goal: Stack all blocks in the green zone.
poses = get_obj_pos_dict()
zx, zy, _ = poses['fixed green zone with obj_id 1'][0]
blocks = sorted([name for name in poses if ' block ' in name], key=lambda name: poses[name][0][2])
def size(name):
    return 0.06 if ' big ' in name else 0.02 if ' tiny ' in name else 0.04
def upright(name):
    return all(min(abs(a) % (np.pi / 2), np.pi / 2 - abs(a) % (np.pi / 2)) < 0.26 for a in poses[name][1][:2])
in_zone = [name for name in blocks if abs(poses[name][0][0] - zx) < 0.06 and abs(poses[name][0][1] - zy) < 0.06]
stacked = abs(poses[blocks[0]][0][2] - size(blocks[0]) / 2) < 0.015 and all(upright(name) for name in blocks)
for lower, upper in zip(blocks, blocks[1:]):
    (x0, y0, z0), (x1, y1, z1) = poses[lower][0], poses[upper][0]
    if math.hypot(x1 - x0, y1 - y0) > 0.02 or abs(z1 - z0 - (size(lower) + size(upper)) / 2) > 0.015:
        stacked = False
judge = stacked and len(in_zone) == len(blocks)
reason = f'{len(in_zone)} of {len(blocks)} blocks in the green zone, stacked: {stacked}'
#@ end

#@ example: stack_not_done
#@ scene: {"objects": [["zone", "orange", 0.45, -0.2], ["block", "cyan", 0.45, -0.2, "small", 0.02], ["block", "pink", 0.6, 0.15], ["zone", "blue", 0.4, 0.3]]}
#@ expect: false
objects = ['fixed orange zone with obj_id 1', 'movable small cyan block with obj_id 2', 'movable small pink block with obj_id 3', 'fixed blue zone with obj_id 4']
# goal: Stack all blocks in the orange zone.
poses = get_obj_pos_dict()
zx, zy, _ = poses['fixed orange zone with obj_id 1'][0]
blocks = sorted([name for name in poses if ' block ' in name], key=lambda name: poses[name][0][2])
outside = [name for name in blocks if abs(poses[name][0][0] - zx) > 0.06 or abs(poses[name][0][1] - zy) > 0.06]
stacked = all(math.hypot(poses[upper][0][0] - poses[lower][0][0], poses[upper][0][1] - poses[lower][0][1]) < 0.02
              and abs(poses[upper][0][2] - poses[lower][0][2] - 0.04) < 0.015 for lower, upper in zip(blocks, blocks[1:]))
judge = not outside and stacked
reason = f'outside the orange zone: {outside}; stacked: {stacked}'
#@ end

#@ example: block_in_bowl
#@ scene: {"objects": [["bowl", "blue", 0.5, -0.1], ["block", "red", 0.5, -0.1, "small", 0.024], ["bowl", "red", 0.4, 0.25], ["block", "green", 0.62, 0.2]]}
#@ expect: true
objects = ['fixed blue bowl with obj_id 1', 'movable small red block with obj_id 2', 'fixed red bowl with obj_id 3', 'movable small green block with obj_id 4']
# goal: Put the red block in the blue bowl.
bx, by, _ = get_obj_pos('fixed blue bowl with obj_id 1')
x, y, _ = get_obj_pos('movable small red block with obj_id 2')
judge = math.hypot(x - bx, y - by) < 0.05
reason = f'the red block is {math.hypot(x - bx, y - by):.3f} m from the blue bowl centre'
#@ end

#@ example: row_wrong_order
#@ scene: {"objects": [["block", "red", 0.65, 0.1], ["block", "green", 0.65, 0.0], ["block", "blue", 0.65, -0.1]]}
#@ expect: false
objects = ['movable small red block with obj_id 1', 'movable small green block with obj_id 2', 'movable small blue block with obj_id 3']
# goal: Line the blocks up along the bottom side from left to right: red, green, blue, 0.1 m apart.
# Left to right is increasing y; the bottom side has large x.
pos = {get_color(name): get_obj_pos(name) for name in objects if ' block ' in name}
ys = [pos[color][1] for color in ['red', 'green', 'blue']]
in_order = all(0.08 < b - a < 0.12 for a, b in zip(ys, ys[1:]))
at_bottom = all(pos[color][0] > 0.6 for color in pos)
judge = in_order and at_bottom
reason = f'y of red, green, blue: {np.round(ys, 3).tolist()}; all at the bottom side: {at_bottom}'
#@ end

<<QUESTION>>
