#!/usr/bin/env python3
"""Writes the decoder's seed corpus (tests/fuzz/corpus/). Independent of the
C++ encoder: it follows docs/firmware.md and uses zlib's CRC-32, so a seed
that the decoder rejects points at a disagreement with the documented format."""
import os, struct, zlib

HERE = os.path.dirname(os.path.abspath(__file__))
SIZES = {1: 372, 2: 1340, 3: 60}


def message(kind, seq, payload):
    body = struct.pack('<BBHI', 3, kind, len(payload), seq) + payload
    return b'\xa5\x5a' + body + struct.pack('<I', zlib.crc32(body))


def sensor(tick, seq):
    q = [(-0.2, 0.7, -1.4)[j % 3] * (1 if j < 6 or j % 3 == 0 else -1) for j in range(12)]
    doubles = q + [0.01 * j for j in range(12)] + [10.0 - j for j in range(12)]
    doubles += [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.02, 0.1, -0.05, 9.81]
    return message(1, seq, struct.pack('<I', tick) + struct.pack('<46d', *doubles))


def command(tick, seq):
    payload = struct.pack('<II', tick, 0) + struct.pack('<60d', *[0.5] * 60)
    payload += struct.pack('<III', 0xF, 0, 4) + struct.pack('<75d', *[0.25] * 75)
    payload += struct.pack('<5I', 4, 4, 0, 0, 0)
    for cell, count, mu, spread in (((-2, 0), 3, 0.2, 0.01), ((5, -1), 1, 0.25, 0.0), ((0, 0), 0, 0.0, 0.0), ((0, 0), 0, 0.0, 0.0)):
        payload += struct.pack('<2iI2d', *cell, count, mu, spread)
    payload += struct.pack('<27I', *range(27))
    return message(2, seq, payload)


def hello(seq):
    return message(3, seq, struct.pack('<11I2d', 1, 3, 25000000, 0, 1, 0, 0, 0, 1, 1, 2048, 0.785, 1.25))


def forged_header(kind=4, length=1536, seq=0):
    """A header with nothing behind it: sync, version, type and a length that type can have."""
    return b'\xa5\x5a' + struct.pack('<BBHI', 3, kind, length, seq)


def mixed_forged_headers(n_bytes):
    """Forged headers of every type, configurations of many lengths, cut to n_bytes."""
    out, k = b'', 0
    while len(out) < n_bytes:
        kind = 1 + k % 4
        out += forged_header(kind, SIZES.get(kind, 1 + (k * 397) % 1536), k)
        k += 1
    return out[:n_bytes]


def burst_mode(length, kind, pattern):
    """The fuzz target's burst mode: it repeats pattern into a burst of length bytes, then sends
    two valid messages (the first of the given kind: 0 sensor, 1 command, 2 Hello, 3 configuration)."""
    return b'\xb7' + struct.pack('<HB', length, kind) + pattern


def main():
    out = os.path.join(HERE, 'corpus')
    os.makedirs(out, exist_ok=True)
    assert len(sensor(0, 0)) == 14 + SIZES[1] and len(command(0, 0)) == 14 + SIZES[2]
    seeds = {
        'sensor': sensor(1, 1),
        'command': command(1, 1),
        'hello': hello(1),
        'stream': hello(1) + sensor(1, 2) + sensor(2, 3) + command(2, 4),
        'truncated_then_good': sensor(1, 1)[:100] + sensor(2, 2),
        'noise_then_good': b'\x00\xa5\xa5\x5a\x01\xff' + sensor(3, 1),
        'out_of_order': sensor(1, 5) + sensor(2, 4) + sensor(3, 5) + sensor(4, 9),
        'bad_crc': sensor(1, 1)[:-1] + b'\x00',
        'config': message(4, 1, bytes(range(200))) + sensor(1, 2),
        # Bursts up to the decoder's buffer size (1550 bytes) and beyond, then valid messages.
        'forged_burst': forged_header() * 117 + sensor(1, 1) + sensor(2, 2),
        'forged_burst_full': forged_header() * 155 + command(1, 1) + sensor(2, 2),
        'mixed_forged_burst': mixed_forged_headers(1550) + message(4, 1, bytes(1536)) + sensor(2, 2),
        'forged_then_cut': forged_header() + message(4, 9, bytes(range(256)) * 6)[:1000] + sensor(1, 1),
        'forged_body': forged_header() * 40 + message(4, 1, forged_header() * 153 + bytes(6)) + sensor(2, 2),
        'burst_mode_forged': burst_mode(1550, 0, forged_header()),
        'burst_mode_dense': burst_mode(6200, 3, forged_header()[:6]),
        'burst_mode_mixed': burst_mode(4000, 1, mixed_forged_headers(60)),
        'burst_mode_sync_pairs': burst_mode(1549, 2, b'\xa5\x5a'),
    }
    for name, data in seeds.items():
        with open(os.path.join(out, name), 'wb') as f:
            f.write(data)


if __name__ == '__main__':
    main()
