#!/usr/bin/env python3
"""A TCP port for a roscore of our own: one nobody listens on now, below the kernel's ephemeral range
(ip_local_port_range), so that no outgoing connection is given it before the master binds it.

Run by node_bench.py, soak.py and test/shell/helpers.bash's free_port: it prints the port."""

import random
import socket


def free_port():
    with open('/proc/sys/net/ipv4/ip_local_port_range') as f:
        low = int(f.read().split()[0])
    for _ in range(1000):
        port = random.randrange(10000, low)
        with socket.socket() as s:
            try:
                s.bind(('127.0.0.1', port))
            except OSError:
                continue
        return port
    raise RuntimeError('no free port in [10000, %d) after 1000 tries' % low)


if __name__ == '__main__':
    print(free_port())
