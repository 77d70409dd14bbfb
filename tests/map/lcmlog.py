"""A minimal reader of LCM logs and of the snapnav messages the localization tests look at (no
LCM Python bindings needed): pose_t, localization_status_t, occupancy_grid_t."""
import struct

SYNC = 0xEDA1DA01


def events(path):
    """(channel, receive utime, payload) of every event."""
    with open(path, 'rb') as f:
        data = f.read()
    i = 0
    while i + 28 <= len(data):
        sync, _, ts, clen, dlen = struct.unpack_from('>IqqII', data, i)
        if sync != SYNC:
            raise ValueError('%s: bad sync at byte %d' % (path, i))
        i += 28
        channel = data[i:i + clen].decode()
        i += clen
        yield channel, ts, data[i:i + dlen]
        i += dlen


class Reader:
    def __init__(self, payload):
        self.b, self.i = payload, 8  # after the fingerprint

    def get(self, fmt):
        v = struct.unpack_from('>' + fmt, self.b, self.i)
        self.i += struct.calcsize('>' + fmt)
        return v if len(v) > 1 else v[0]

    def string(self):
        n = self.get('i')
        s = self.b[self.i:self.i + n - 1].decode()
        self.i += n
        return s


def pose(payload):
    r = Reader(payload)
    utime = r.get('q')
    estimator, frame = r.string(), r.string()
    x, y, th = r.get('ddd')
    return {'utime': utime, 'estimator': estimator, 'frame': frame, 'x': x, 'y': y, 'theta': th}


def localization_status(payload):
    r = Reader(payload)
    utime = r.get('q')
    state = r.get('b')
    score, gscore, gamb = r.get('ddd')
    candidates = r.get('i')
    global_ms = r.get('d')
    bad_scans = r.get('i')
    sigma_m, sigma_deg = r.get('dd')
    scans, searches, relocalizations, losses = r.get('qqqq')
    return {'utime': utime, 'state': state, 'score': score, 'global_score': gscore, 'global_ambiguity': gamb,
            'global_candidates': candidates, 'global_ms': global_ms, 'bad_scans': bad_scans, 'scans': scans,
            'global_searches': searches, 'relocalizations': relocalizations, 'losses': losses, 'map': r.string()}


def occupancy_grid(payload):
    r = Reader(payload)
    utime = r.get('q')
    frame, source = r.string(), r.string()
    res = r.get('f')
    ox, oy, oth = r.get('ddd')
    w, h, n = r.get('iii')
    cells = struct.unpack_from('>%db' % n, r.b, r.i)
    return {'utime': utime, 'frame': frame, 'source': source, 'resolution': res, 'origin': (ox, oy, oth),
            'width': w, 'height': h, 'cells': cells}
