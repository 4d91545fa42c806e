#!/usr/bin/env python3
"""A TCP proxy on loopback that makes a local server look far away: each
burst of bytes a client sends (a request) waits LATENCY seconds before it
is passed on, a new connection waits LATENCY before its upstream one is
opened (the handshake's round trip), and the bytes coming back share one
token bucket of MBIT megabits a second over every connection (a link's
capacity, not a per-connection cap). It knows nothing of HTTP, so
keep-alive, ranges and any number of connections pass as they are.

    python3 bench/throttle_proxy.py UPSTREAM_PORT [--latency 0.05] [--mbit 100]
        [--port PORT]

Prints "listening PORT" once it accepts, then serves until killed (SIGTERM).
Used by bench/remote_2048.py (issue 79's "a local proxy adds 50 ms a
request and caps 100 Mbit/s").
"""
import argparse
import asyncio
import signal
import sys


class Link:
    """The shared capacity: each piece of N bytes going back to a client
    takes N / rate seconds of the link, in the order asked."""

    def __init__(self, mbit):
        self.rate = mbit * 1e6 / 8.0
        self.free_at = 0.0

    async def pass_bytes(self, n):
        loop = asyncio.get_running_loop()
        now = loop.time()
        start = max(now, self.free_at)
        self.free_at = start + n / self.rate
        if self.free_at > now:
            await asyncio.sleep(self.free_at - now)


async def pump(reader, writer, delay=0.0, link=None, piece=16384):
    try:
        while True:
            data = await reader.read(piece)
            if not data:
                break
            if delay:
                await asyncio.sleep(delay)
            if link:
                await link.pass_bytes(len(data))
            writer.write(data)
            await writer.drain()
    except (ConnectionError, asyncio.CancelledError):
        pass
    finally:
        try:
            writer.close()
        except Exception:
            pass


async def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("upstream", type=int)
    ap.add_argument("--latency", type=float, default=0.05)
    ap.add_argument("--mbit", type=float, default=100.0)
    ap.add_argument("--port", type=int, default=0)
    a = ap.parse_args()
    link = Link(a.mbit)

    async def serve(cr, cw):
        await asyncio.sleep(a.latency)
        try:
            ur, uw = await asyncio.open_connection("127.0.0.1", a.upstream)
        except OSError:
            cw.close()
            return
        up = asyncio.ensure_future(pump(cr, uw, delay=a.latency))
        down = asyncio.ensure_future(pump(ur, cw, link=link))
        await asyncio.wait([up, down], return_when=asyncio.FIRST_COMPLETED)
        for t in (up, down):
            t.cancel()
        for w in (uw, cw):
            w.close()

    srv = await asyncio.start_server(serve, "127.0.0.1", a.port, backlog=1024)
    print("listening", srv.sockets[0].getsockname()[1], flush=True)
    stop = asyncio.Event()
    asyncio.get_running_loop().add_signal_handler(signal.SIGTERM, stop.set)
    async with srv:
        await stop.wait()


if __name__ == "__main__":
    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        sys.exit(0)
