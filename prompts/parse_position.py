import numpy as np, math
from shapely.geometry import Point, Polygon, LineString, box
from env_utils import get_obj_names, get_obj_pos, get_bbox, denormalize, is_target_occupied, get_random_free_pos

# Set ret_val to the position described in the last comment: [x, y] or [x, y, z] (metres), a list of positions, or a pose ([x, y, z], quaternion (x, y, z, w)).
# Table: x from 0.25 (top/rear) to 0.75 (bottom/front), y from -0.5 (left) to 0.5 (right), z up, table top z = 0.
# denormalize([u, v]) -> [x, y] for u = 0 (left) .. 1 (right) and v = 0 (bottom) .. 1 (top); corners and sides keep 0.1 from the edges.
# get_obj_pos(name) -> [x, y, z] of the object's centre. get_bbox(name) -> (xmin, ymin, zmin, xmax, ymax, zmax).
# get_random_free_pos(targ=None, area=(xmin, ymin, xmax, ymax)) -> a free [x, y, 0] in the area, away from every object.
# is_target_occupied([x, y], r) -> names of the objects within r of the point.
# Rules: no imports; only these functions, np, math and shapely.

#@ stop: ["\n\nobjects = ["]

#@ example: top_right_corner
#@ scene: {"objects": [["block", "blue", 0.55, -0.2], ["block", "yellow", 0.4, 0.1], ["block", "red", 0.6, 0.25]]}
#@ expect: [0.3, 0.4]
objects = ['movable small blue block with obj_id 1', 'movable small yellow block with obj_id 2', 'movable small red block with obj_id 3']
# the top right corner.
ret_val = denormalize([0.9, 0.9])
#@ end

#@ example: left_of_block
#@ scene: {"objects": [["block", "red", 0.5, 0.1], ["zone", "green", 0.4, -0.25]]}
#@ expect: [0.5, 0.0, 0.02]
objects = ['movable small red block with obj_id 1', 'fixed green zone with obj_id 2']
# a point 0.1 m to the left of the red block.
x, y, z = get_obj_pos('movable small red block with obj_id 1')
ret_val = [x, y - 0.1, z]
#@ end

#@ example: circle_around_zone
#@ scene: {"objects": [["block", "red", 0.35, 0.3], ["zone", "green", 0.5, -0.1]]}
#@ expect: [[0.6, -0.1], [0.5, 0.0], [0.4, -0.1], [0.5, -0.2]]
objects = ['movable small red block with obj_id 1', 'fixed green zone with obj_id 2']
# 4 points on a circle of radius 0.1 around the green zone.
cx, cy, _ = get_obj_pos('fixed green zone with obj_id 2')
angles = np.linspace(0, 2 * np.pi, 4, endpoint=False)
ret_val = [[cx + 0.1 * np.cos(a), cy + 0.1 * np.sin(a)] for a in angles]
#@ end

#@ example: between_bowls
#@ scene: {"objects": [["bowl", "blue", 0.4, -0.3], ["bowl", "pink", 0.6, 0.1], ["block", "orange", 0.35, 0.3]]}
#@ expect: [0.5, -0.1]
objects = ['fixed blue bowl with obj_id 1', 'fixed pink bowl with obj_id 2', 'movable small orange block with obj_id 3']
# the middle between the two bowls.
bowls = [name for name in objects if ' bowl ' in name]
ret_val = np.mean([get_obj_pos(bowl)[:2] for bowl in bowls], axis=0).tolist()
#@ end

#@ example: free_right_half
#@ scene: {"objects": [["block", "red", 0.5, 0.2], ["zone", "green", 0.4, 0.35], ["block", "blue", 0.6, -0.2]]}
#@ check: ret_val[1] > 0 and is_target_occupied(ret_val, 0.04) == []
objects = ['movable small red block with obj_id 1', 'fixed green zone with obj_id 2', 'movable small blue block with obj_id 3']
# a free spot in the right half.
ret_val = get_random_free_pos(area=(0.25, 0.0, 0.75, 0.5))
#@ end

<<QUESTION>>
