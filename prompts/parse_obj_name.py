import numpy as np, math
from env_utils import get_obj_names, get_obj_pos, get_obj_rot, get_bbox, get_color, get_obj_positions_np, is_target_occupied

# Set ret_val to the object names that match the description in the last comment: a list of names, or one name for "the <one object>".
# Names look like 'movable small blue block with obj_id 3' (blocks: tiny 0.02 m, small 0.04 m, big 0.06 m cubes) and 'fixed red zone with obj_id 1'.
# get_obj_pos(name) -> [x, y, z] of the centre (metres). get_color(name) -> 'blue'. get_bbox(name) -> (xmin, ymin, zmin, xmax, ymax, zmax).
# is_target_occupied(name) -> names of the objects overlapping that object (e.g. the blocks in a zone).
# Table: x from 0.25 (top/rear) to 0.75 (bottom/front), y from -0.5 (left) to 0.5 (right), z up. left = smaller y, right = larger y, front = larger x, rear = smaller x.
# "horizontal distance" is measured along y, "front-back distance" along x.
# Warm colours: red, yellow, orange, brown, pink, gold. Cool colours: blue, green, cyan, purple, gray, violet, indigo, silver.
# Rules: no imports; only these functions, np and math. Use the exact names from objects.

#@ stop: ["\n\nobjects = ["]

#@ example: left_of_bowl
#@ scene: {"objects": [["bowl", "green", 0.5, 0.0], ["block", "red", 0.4, -0.25], ["block", "blue", 0.62, -0.15], ["block", "yellow", 0.42, 0.22], ["bowl", "purple", 0.62, 0.3]]}
#@ expect: ["movable small red block with obj_id 2", "movable small blue block with obj_id 3"]
objects = ['fixed green bowl with obj_id 1', 'movable small red block with obj_id 2', 'movable small blue block with obj_id 3', 'movable small yellow block with obj_id 4', 'fixed purple bowl with obj_id 5']
# the blocks left of the green bowl.
bowl_y = get_obj_pos('fixed green bowl with obj_id 1')[1]
ret_val = [name for name in objects if ' block ' in name and get_obj_pos(name)[1] < bowl_y]
#@ end

#@ example: in_front_by_distance
#@ scene: {"objects": [["block", "purple", 0.45, 0.0], ["block", "red", 0.6, 0.2], ["block", "blue", 0.5, -0.3], ["block", "green", 0.35, 0.1], ["block", "yellow", 0.68, -0.15]]}
#@ expect: ["movable small red block with obj_id 2", "movable small yellow block with obj_id 5"]
objects = ['movable small purple block with obj_id 1', 'movable small red block with obj_id 2', 'movable small blue block with obj_id 3', 'movable small green block with obj_id 4', 'movable small yellow block with obj_id 5']
# the blocks in front of the purple block with front-back distance larger than 0.1.
# front = larger x; the front-back distance is the difference in x.
ref_x = get_obj_pos('movable small purple block with obj_id 1')[0]
ret_val = [name for name in objects if ' block ' in name and get_obj_pos(name)[0] - ref_x > 0.1]
#@ end

#@ example: closest_bowl
#@ scene: {"objects": [["bowl", "red", 0.35, -0.25], ["bowl", "yellow", 0.6, 0.1], ["block", "blue", 0.55, -0.1], ["bowl", "gray", 0.4, 0.3]]}
#@ expect: "fixed yellow bowl with obj_id 2"
objects = ['fixed red bowl with obj_id 1', 'fixed yellow bowl with obj_id 2', 'movable small blue block with obj_id 3', 'fixed gray bowl with obj_id 4']
# the bowl closest to the blue block.
block_xy = np.array(get_obj_pos('movable small blue block with obj_id 3')[:2])
bowls = [name for name in objects if ' bowl ' in name]
ret_val = min(bowls, key=lambda bowl: np.linalg.norm(np.array(get_obj_pos(bowl)[:2]) - block_xy))
#@ end

#@ example: big_blocks_in_zone
#@ scene: {"objects": [["zone", "blue", 0.5, 0.2], ["block", "green", 0.5, 0.2, "big"], ["block", "red", 0.4, -0.2, "big"], ["block", "cyan", 0.6, -0.05, "small"]]}
#@ expect: ["movable big green block with obj_id 2"]
objects = ['fixed blue zone with obj_id 1', 'movable big green block with obj_id 2', 'movable big red block with obj_id 3', 'movable small cyan block with obj_id 4']
# the big blocks in the blue zone.
ret_val = [name for name in is_target_occupied('fixed blue zone with obj_id 1') if ' big ' in name and ' block ' in name]
#@ end

<<QUESTION>>
