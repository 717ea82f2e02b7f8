import numpy as np, math, itertools
from shapely.geometry import Point, Polygon, LineString, box
from env_utils import get_obj_names, get_obj_pos, get_obj_rot, get_bbox, get_color, get_obj_positions_np, is_target_occupied, get_random_free_pos, denormalize

# Define the function used in the last comment, so that the call works. Return values; do not print.
# get_obj_names() -> names like 'movable small blue block with obj_id 3', 'fixed red zone with obj_id 1'. get_obj_pos(name) -> [x, y, z] (metres).
# get_color(name) -> 'blue'. get_bbox(name) -> (xmin, ymin, zmin, xmax, ymax, zmax). is_target_occupied(name) -> names of the objects overlapping that object.
# Table: x from 0.25 (top) to 0.75 (bottom), y from -0.5 (left) to 0.5 (right), z up.
# Rules: no imports and no classes; only these functions, np, math, itertools and shapely. You may call other helper functions that do not exist yet.

#@ stop: ["\n\n# define function:"]

#@ example: get_distance
#@ scene: {"objects": [["block", "red", 0.5, 0.1]]}
#@ check: abs(get_distance([0.3, 0.0, 0.0], [0.6, 0.4, 0.02]) - 0.5) < 1e-9
# define function: dist = get_distance(get_obj_pos(block_a), get_obj_pos(block_b)).
def get_distance(pos_a, pos_b):
    # distance in the xy plane
    return float(np.linalg.norm(np.array(pos_a[:2]) - np.array(pos_b[:2])))
#@ end

#@ example: get_blocks_in_zone
#@ scene: {"objects": [["zone", "red", 0.5, 0.2, null, null, 0.785], ["block", "blue", 0.52, 0.18], ["block", "yellow", 0.56, 0.26], ["block", "green", 0.4, -0.2]]}
#@ check: get_blocks_in_zone('fixed red zone with obj_id 1') == ['movable small blue block with obj_id 2']
# define function: inside = get_blocks_in_zone('fixed red zone with obj_id 1').
def get_blocks_in_zone(zone):
    # In a zone = the centre inside the zone's square, which is turned by the zone's yaw;
    # the world box of a turned square is larger than the square, so use the zone's own axes.
    cx, cy, _ = get_obj_pos(zone)
    q = get_obj_rot(zone)
    yaw = 2 * math.atan2(q[2], q[3])
    xmin, _, _, xmax, _, _ = get_bbox(zone)
    half = (xmax - xmin) / (abs(math.cos(yaw)) + abs(math.sin(yaw))) / 2
    inside = []
    for name in get_obj_names():
        x, y, _ = get_obj_pos(name)
        u = (x - cx) * math.cos(yaw) + (y - cy) * math.sin(yaw)
        v = -(x - cx) * math.sin(yaw) + (y - cy) * math.cos(yaw)
        if ' block ' in name and abs(u) <= half and abs(v) <= half:
            inside.append(name)
    return inside
#@ end

#@ example: get_circle_points
#@ scene: {"objects": [["block", "red", 0.5, 0.1]]}
#@ check: len(get_circle_points([0.5, 0.0], 0.1, 6)) == 6 and all(abs(math.hypot(p[0] - 0.5, p[1]) - 0.1) < 1e-9 for p in get_circle_points([0.5, 0.0], 0.1, 6))
# define function: points = get_circle_points(center, 0.1, 6).
def get_circle_points(center, radius, n):
    angles = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return [[center[0] + radius * np.cos(a), center[1] + radius * np.sin(a)] for a in angles]
#@ end

#@ example: get_top_block
#@ scene: {"objects": [["block", "red", 0.55, 0.1, "small", 0.02], ["block", "green", 0.55, 0.1, "small", 0.06], ["block", "blue", 0.4, -0.2]]}
#@ check: get_top_block(['movable small red block with obj_id 1', 'movable small green block with obj_id 2']) == 'movable small green block with obj_id 2'
# define function: top = get_top_block(tower_blocks).
def get_top_block(names):
    return max(names, key=lambda name: get_obj_pos(name)[2])
#@ end

<<QUESTION>>
