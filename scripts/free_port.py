#!/usr/bin/env python3
"""Prints a TCP port that is free on the loopback now and that the kernel will not hand out
by itself: one below the ephemeral range (/proc/sys/net/ipv4/ip_local_port_range).

Why not bind(0): that port comes from the ephemeral range, which every node of a launch draws
from too (roscpp's TCPROS and XML-RPC servers bind port 0, every outgoing connection takes a
source port there). Between this script releasing the port and the room server (or the ROS
master) binding it, a node of the same launch could take it: the room server then cannot listen
and the bridge talks to a ROS node's socket ("handshake: The socket was closed due to a
timeout"), as seen once in CI's fault matrix. Below the ephemeral range only an explicit bind
can take the port. The draw is random (no seed: it changes no output), so two runs at once
rarely try the same port, and a port that does not bind is skipped.

Usage: free_port.py [--host 127.0.0.1]
"""
import random
import socket
import sys

LOWEST = 10000  # below: well-known and registered services' usual ports


def ephemeral_low():
    try:
        with open("/proc/sys/net/ipv4/ip_local_port_range") as f:
            return int(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return 32768  # Linux's default


def bindable(host, port):
    s = socket.socket()
    try:
        s.bind((host, port))
        return True
    except OSError:
        return False
    finally:
        s.close()


def main():
    host = sys.argv[2] if len(sys.argv) > 2 and sys.argv[1] == "--host" else "127.0.0.1"
    high = ephemeral_low() - 1
    draw = random.SystemRandom()
    if high > LOWEST:
        for _ in range(200):
            port = draw.randint(LOWEST, high)
            if bindable(host, port):
                print(port)
                return 0
    # No room below the ephemeral range (an unusual ip_local_port_range): the kernel's pick.
    s = socket.socket()
    s.bind((host, 0))
    print(s.getsockname()[1])
    s.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
