#!/usr/bin/env python3
"""A TCP relay (asyncio): every connection accepted on --listen is forwarded, both ways, to --to.

tests/zenoh/faults.sh links router B to router A through it, so killing this process cuts the
link between the two sites (both TCP connections close at once, as a dropped line would end
them) without touching either router; starting it again on the same port restores the link
(the routers reconnect by themselves). Prints one line when listening, then runs until killed.

  usage: tcp_relay.py --listen 127.0.0.1:7449 --to 127.0.0.1:7447
Run only inside a loopback-only network namespace (../shared/tools/netns-run).
"""
import argparse
import asyncio
import socket
import sys

CHUNK = 65536


def host_port(text):
    host, _, port = text.rpartition(":")
    return host or "127.0.0.1", int(port)


def nodelay(writer):
    sock = writer.get_extra_info("socket")
    if sock is not None:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)


async def pipe(reader, writer):
    """Copy until EOF or an error."""
    try:
        while True:
            data = await reader.read(CHUNK)
            if not data:
                return
            writer.write(data)
            await writer.drain()
    except (ConnectionError, OSError):
        return


async def handle(target, client_reader, client_writer):
    """One accepted connection: open the target, pipe both ways, close both when either ends."""
    nodelay(client_writer)
    try:
        up_reader, up_writer = await asyncio.open_connection(*target)
    except OSError:
        client_writer.close()  # the far side is down: the connecting side sees the link drop
        return
    nodelay(up_writer)
    tasks = [asyncio.create_task(pipe(client_reader, up_writer)),
             asyncio.create_task(pipe(up_reader, client_writer))]
    await asyncio.wait(tasks, return_when=asyncio.FIRST_COMPLETED)
    for task in tasks:
        task.cancel()
    for writer in (client_writer, up_writer):
        writer.close()


async def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--listen", required=True, help="HOST:PORT to accept connections on")
    ap.add_argument("--to", required=True, help="HOST:PORT to forward them to")
    a = ap.parse_args()
    target = host_port(a.to)
    host, port = host_port(a.listen)
    server = await asyncio.start_server(lambda r, w: handle(target, r, w), host, port,
                                        reuse_address=True)
    print(f"tcp_relay: {host}:{port} -> {target[0]}:{target[1]}", flush=True)
    async with server:
        await server.serve_forever()


if __name__ == "__main__":
    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        sys.exit(0)
