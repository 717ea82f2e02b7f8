# The helpers of the low-level reference plans, on the low-level API only: the reference agent runs
# this file before each plan of this folder (capmj.agents.reference.reference_plan).
# The suction tool points down; a tool pose is [x, y, z] of the tip and a yaw.  pick() takes an
# object from above with a guarded descent; place() carries it over a point, turns it, lowers it
# until it touches what is below and lets go.  Blocks look the same every quarter turn.


def obj(name):
    return get_object(name)


def quarter(angle):
    # the angle reduced to [-pi/4, pi/4): a block turned by a quarter turn looks the same
    return (angle + math.pi / 4) % (math.pi / 2) - math.pi / 4


placed = {}  # name -> (x, y, half side, top) of each block this plan put down, where it let go of it


def pick(name):
    placed.pop(name, None)
    o = obj(name)
    x, y, _ = o['position']
    top = o['bbox'][5]
    _, tool_yaw = get_ee_pose()
    yaw = quarter(tool_yaw)  # the cup is round: keep the wrist near the middle of its range
    move_to_pose([x, y, top + 0.03], yaw)
    move_until_contact([x, y, top - 0.02], yaw)
    if not suction_on():
        raise RuntimeError(f'the suction did not grip {name}')
    return yaw


def surface_under(x, y, held, skip):
    # the highest top of an object whose box comes within reach of the held object centred at (x, y)
    # (its half diagonal and 1 cm: its neighbours too), 0 for the table: the planned approach ends
    # above all of them, and a guarded descent goes the rest of the way.  What this plan put down
    # counts too, as it left it: the cameras may not tell blocks packed close together apart.
    reach = 1.5 * max(held['half_size'][0], held['half_size'][1]) + 0.01
    tops = [0.0]
    for o in get_objects():
        b = o['bbox']
        if o['name'] != skip and b[0] - reach <= x <= b[3] + reach and b[1] - reach <= y <= b[4] + reach:
            tops.append(b[5])
    for px, py, h, top in placed.values():
        if abs(px - x) <= h * 1.5 + reach and abs(py - y) <= h * 1.5 + reach:
            tops.append(top)
    return max(tops)


def place(name, x, y, yaw=None):
    # the held object `name` centred over (x, y), turned to `yaw` (None: as it is), lowered onto what is there
    o = obj(name)
    tip, tool_yaw = get_ee_pose()
    turn = 0.0 if yaw is None else quarter(yaw - o['yaw'])
    dx, dy = o['position'][0] - tip[0], o['position'][1] - tip[1]  # the object's centre from the tip
    c, s = math.cos(turn), math.sin(turn)
    tx, ty = x - (c * dx - s * dy), y - (s * dx + c * dy)
    hang = tip[2] - o['bbox'][2]  # from the tip down to the object's bottom
    surface = surface_under(x, y, o, name)
    move_to_pose([tx, ty, surface + hang + 0.03], tool_yaw + turn)
    move_until_contact([tx, ty, hang - 0.04], tool_yaw + turn)
    bottom = get_ee_pose()[0][2] - hang
    suction_off()
    placed[name] = (x, y, o['half_size'][0], bottom + 2 * o['half_size'][2])


def put(name, x, y, yaw=None):
    pick(name)
    place(name, x, y, yaw)


def put_on(name, target):
    # on a block or a zone: centred, turned like it; into a bowl (or onto anything else): centred, as it is
    t = obj(target)
    pick(name)
    place(name, t['position'][0], t['position'][1], t['yaw'] if t['kind'] in ('block', 'zone') else None)


def free_spot(area, r=0.045, taken=()):
    # a point of area (xmin, ymin, xmax, ymax), r from its border, at least r from every object's box
    # and 2 r from the points in `taken`; the free one nearest the area's centre
    xmin, ymin, xmax, ymax = area
    boxes = [o['bbox'] for o in get_objects()]
    cx, cy = (xmin + xmax) / 2, (ymin + ymax) / 2
    best = None
    for i in range(15):
        for j in range(15):
            x = xmin + r + (xmax - xmin - 2 * r) * i / 14
            y = ymin + r + (ymax - ymin - 2 * r) * j / 14
            gaps = [math.hypot(max(b[0] - x, 0.0, x - b[3]), max(b[1] - y, 0.0, y - b[4])) for b in boxes]
            if min(gaps + [1.0]) < r or any(math.hypot(x - p[0], y - p[1]) < 2 * r for p in taken):
                continue
            d = math.hypot(x - cx, y - cy)
            if best is None or d < best[0]:
                best = (d, [x, y])
    if best is None:
        raise RuntimeError(f'no free spot in {area}')
    return best[1]
