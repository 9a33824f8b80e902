#!/usr/bin/env python3
"""Room-scale benchmark on loopback (issue 19); run through scripts/bench-room.

Starts vistel-server on a free loopback port, then bots (vistel-bot --count K, several
processes, each streaming a gesture clip) into N rooms of M members, waits for them to
finish, stops the server and prints one JSON object:

  members_connected        participants that went live (of members * rooms)
  join_s {p50,p99,max}     from a participant's start to its session going live
  rejoins                  joins refused and tried again (all participants)
  tick_ms {p50,p99}        the server's own measure of a room tick's work
  server_cpu_us_per_member_tick
                           server process CPU time / (ticks * members), over the run
  latency_ms {p50,p99}     a posture's capture (sender, server clock) to its arrival at
                           another member (all pairs, merged histograms, 0.05 ms bins)
  bytes_per_member_frame {up,down}
                           up: UDP payload per posture sent; down: UDP payload a member
                           receives per tick period (1/60 s) while live
  snapshots_dropped        datagrams the server's socket refused to send (send errors)
  rejected_datagrams       datagrams the bots could not parse (should be 0)

Only loopback addresses are used. Bots run for the duration plus the join window, at
niceness 5 (--bots-nice): they stand for clients on other machines, and on a small machine
a hundred of them would otherwise queue the server's threads behind theirs.
"""

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time


def percentile(values, p):
    if not values:
        return 0.0
    ordered = sorted(values)
    rank = max(0, min(len(ordered) - 1, int(round(p / 100.0 * (len(ordered) - 1)))))
    return ordered[rank]


def histogram_percentile(bins, bin_ms, p):
    total = sum(bins.values())
    if total == 0:
        return 0.0
    rank = max(1, int(-(-p * total // 100)))  # ceil
    seen = 0
    for index in sorted(bins):
        seen += bins[index]
        if seen >= rank:
            return (index + 0.5) * bin_ms
    return (max(bins) + 0.5) * bin_ms


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default="build/release")
    parser.add_argument("--members", type=int, default=16, help="members per room")
    parser.add_argument("--rooms", type=int, default=1)
    parser.add_argument("--duration", type=float, default=10.0, help="seconds of streaming")
    parser.add_argument("--join-at-once", action="store_true",
                        help="start every bot process at the same moment")
    parser.add_argument("--per-process", type=int, default=25,
                        help="participants per bot process")
    parser.add_argument("--json", help="also write the JSON here")
    parser.add_argument("--bots-nice", type=int, default=5,
                        help="niceness of the bot processes (0: none); the bots stand for "
                             "remote clients, so by default they yield to the server")
    args = parser.parse_args()
    if args.members < 1 or args.rooms < 1 or args.duration <= 0 or args.per_process < 1:
        parser.error("--members, --rooms, --per-process must be >= 1 and --duration > 0")

    build = args.build
    server_bin = os.path.join(build, "vistel-server")
    bot_bin = os.path.join(build, "vistel-bot")
    clips_dir = os.path.join(build, "data", "gestures")
    for path in (server_bin, bot_bin, clips_dir):
        if not os.path.exists(path):
            sys.exit(f"bench-room: {path} is missing (build first: scripts/bench-room does)")
    clips = sorted(os.path.join(clips_dir, f) for f in os.listdir(clips_dir)
                   if f.endswith(".bvh"))
    if not clips:
        sys.exit(f"bench-room: no .bvh clip in {clips_dir}")

    work = tempfile.mkdtemp(prefix="vistel-bench-room-")
    total = args.members * args.rooms
    config = os.path.join(work, "server.toml")
    with open(config, "w") as f:
        f.write("[network]\nbind = \"127.0.0.1\"\nport = 0\n")
        f.write(f"[limits]\nmax_members_per_room = {min(255, max(args.members, 1))}\n")
        f.write(f"max_members = {max(1024, total)}\nmax_rooms = {max(64, args.rooms)}\n")
        f.write("[session]\nstats_interval_s = 5.0\n")
    server_stats = os.path.join(work, "server.json")
    server_log = open(os.path.join(work, "server.log"), "w")
    server = subprocess.Popen([server_bin, "--config", config, "--stats-json", server_stats],
                              stdout=subprocess.PIPE, stderr=server_log, text=True)
    line = server.stdout.readline()
    if "listening on" not in line:
        server.kill()
        sys.exit(f"bench-room: the server did not start: {line!r} (log in {work})")
    address = line.strip().split()[-1]

    # Bot processes: each room's members in groups of --per-process.
    bots = []
    reports = []
    start = time.monotonic()
    launched = 0
    for room in range(args.rooms):
        left = args.members
        group = 0
        while left > 0:
            count = min(left, args.per_process)
            left -= count
            report = os.path.join(work, f"bot-{room}-{group}.json")
            clip = clips[(room + group) % len(clips)]
            cmd = [bot_bin, "--server", address, "--room", f"bench-{room}",
                   "--name", f"r{room}g{group}", "--count", str(count), "--bvh", clip,
                   "--loop", "--duration", str(args.duration + 3.0), "--stats-json", report]
            if count == 1:
                cmd[cmd.index("--name") + 1] = f"r{room}g{group}-1"
            log = open(os.path.join(work, f"bot-{room}-{group}.log"), "w")
            if not args.join_at_once and launched > 0:
                time.sleep(0.25)
            if args.bots_nice != 0:
                cmd = ["nice", "-n", str(args.bots_nice)] + cmd
            bots.append(subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT))
            reports.append(report)
            launched += 1
            group += 1
    for bot in bots:
        bot.wait()
    elapsed = time.monotonic() - start
    server.send_signal(signal.SIGINT)
    try:
        server.wait(timeout=15)
    except subprocess.TimeoutExpired:
        server.kill()
    server_log.close()

    # Gather.
    participants = []
    bins = {}
    bin_ms = 0.05
    for report in reports:
        if not os.path.exists(report):
            continue
        with open(report) as f:
            doc = json.load(f)
        participants.extend(doc["participants"])
        bin_ms = doc["latency_histogram"]["bin_ms"]
        for index, count in doc["latency_histogram"]["bins"]:
            bins[index] = bins.get(index, 0) + count
    with open(server_stats) as f:
        srv = json.load(f)
    joined = [p for p in participants if p["join_s"] >= 0]
    joins = [p["join_s"] for p in joined]
    sent = sum(p["postures_sent"] for p in participants)
    up_bytes = sum(p["posture_bytes_sent"] for p in participants)
    down_bytes = sum(p["datagram_bytes_received"] for p in participants)
    live_frames = sum(p["live_s"] for p in participants) * 60.0
    result = {
        "members": args.members,
        "rooms": args.rooms,
        "duration_s": args.duration,
        "join_at_once": args.join_at_once,
        "members_connected": len(joined),
        "join_s": {"p50": round(percentile(joins, 50), 3), "p99": round(percentile(joins, 99), 3),
                   "max": round(max(joins) if joins else 0.0, 3)},
        "rejoins": sum(p["rejoins"] for p in participants),
        "tick_ms": {"p50": srv["tick_ms"]["p50"], "p99": srv["tick_ms"]["p99"]},
        "server_cpu_us_per_member_tick": srv["cpu_us_per_member_tick"],
        "latency_ms": {"p50": round(histogram_percentile(bins, bin_ms, 50), 2),
                       "p99": round(histogram_percentile(bins, bin_ms, 99), 2),
                       "samples": sum(bins.values())},
        "bytes_per_member_frame": {
            "up": round(up_bytes / sent, 1) if sent else 0.0,
            "down": round(down_bytes / live_frames, 1) if live_frames else 0.0},
        "snapshots_dropped": srv["send_failures"],
        "rejected_datagrams": sum(p.get("datagrams_rejected", 0) for p in participants),
        "errors": sorted({p["error"] for p in participants if p["error"]})[:5],
        "bots_nice": args.bots_nice,
        "wall_s": round(elapsed, 1),
        "logs": work,
    }
    text = json.dumps(result, indent=2)
    print(text)
    if args.json:
        with open(args.json, "w") as f:
            f.write(text + "\n")
    return 0 if len(joined) == total else 1


if __name__ == "__main__":
    sys.exit(main())
