"""Benchmark of the ROS node, run as a user would: a node process and a client over DDS.

``python -m brake_sim_ros.studies.node_bench [--duration S] [--scenario NAME] [--afap-seconds S]
[--no-measured] [--sensors-overhead ROUNDS] [--long-run S [--report-every S]]``

Prints:
    * CPU use of the node process at real-time factor 1, in % of one core, from
      ``/proc/<pid>/stat`` (user + system time) over the measured run;
    * real-time factor and deadline misses over that run (``--duration``, default 60 s),
      from the node's own counters, plus samples received and lost by the client;
    * command-to-effect latency: wall time from publishing an ActuationCommand to the
      arrival of the first BrakeState whose actuation force equals the command (the
      chunk that starts applying it carries its state; PivotForceChunk has no actuation
      field);
    * the highest real-time factor: the ceiling measured as fast as possible, then a
      search down from 80 % of it for the highest factor held within 2 % with deadline
      misses on fewer than 1 % of the chunks, every topic published and subscribed.

With ``--sensors-overhead ROUNDS`` it prints instead what the sensors (``~/measured``) cost
the node: ROUNDS pairs of real-time runs of ``--duration`` seconds, one node without and
one with ``publish_measured``, alternated so that drifts of the machine's load fall on
both, and the extra CPU of the sensors in % of the node's CPU without them.

With ``--long-run S`` it prints instead how a ``continuous`` node holds up over S wall
seconds at real-time factor 1 (an hour: ``--long-run 3600``): every ``--report-every``
seconds the simulated time, the real-time factor and deadline misses over the interval, the
samples the client lost, and the node's resident memory (``VmRSS``); at the end the memory's
growth from the first report to the last and its least-squares slope, MB per hour.

The client subscribes to every topic with the REP 2003 consumer QoS, so the node does
all of its publishing work. Both processes share the machine's cores.
"""

from __future__ import annotations

import contextlib
import math
import os
import signal
import statistics
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from brake_sim_ros.command_line import Parser
from brake_sim_ros.ros.harness import NodeProcess, SimClient, domain_id_for

WARM_UP_S = 2.0


def resident_mb(pid: int) -> float:
    """Resident memory of a process, MB (Linux /proc, ``VmRSS``)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    raise RuntimeError(f"no VmRSS for process {pid}")


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process, s (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    ticks = int(fields[11]) + int(fields[12])  # utime, stime (fields 14 and 15 of stat)
    return ticks / os.sysconf("SC_CLK_TCK")


class _Window:
    """Node counters, client counters and CPU time between two instants."""

    def __init__(self, client: SimClient, pid: int) -> None:
        # opened and closed on the arrival of a /diagnostics message, so that the node's
        # counters and the wall and CPU clocks cover the same interval
        self.client, self.pid = client, pid
        self.diag0 = client.next_diagnostics()
        self.wall0 = time.monotonic()
        self.cpu0 = cpu_seconds(pid)
        self.samples0, self.gaps0 = client.sample_count, client.gaps

    def close(self) -> dict[str, float]:
        diag1 = self.client.next_diagnostics()
        wall = time.monotonic() - self.wall0
        dt = 1.0 / float(diag1["sample_rate_hz"])
        steps = int(diag1["samples_done"]) - int(self.diag0["samples_done"])
        return {
            "wall_s": wall,
            "cpu_pct": 100.0 * (cpu_seconds(self.pid) - self.cpu0) / wall,
            "rtf": steps * dt / wall,
            "deadline_misses": int(diag1["deadline_misses"]) - int(self.diag0["deadline_misses"]),
            "chunks": int(diag1["chunks_published"]) - int(self.diag0["chunks_published"]),
            "slips": int(diag1["slips"]) - int(self.diag0["slips"]),
            "steps": steps,
            "received": self.client.sample_count - self.samples0,
            "gaps": self.client.gaps - self.gaps0,
        }


def _latency(client: SimClient, count: int) -> list[float]:
    """Seconds from publishing a command to the first state that shows it."""
    out = []
    for i in range(count):
        force = 200.0 + 10.0 * i  # distinct, within any scenario's limit
        client.rx.states.clear()
        client.rx.state_times.clear()
        t0 = time.monotonic()
        client.command(force, force)

        def shows(state, force=force) -> bool:
            # shares sum to 1, so left + right = 2 x command whatever the share defect
            total = state.left_actuation_force_n + state.right_actuation_force_n
            return abs(total - 2.0 * force) < 1e-6

        client.wait_for(
            lambda: any(shows(s) for s in client.rx.states),
            5.0,
            f"state with the commanded force {force} N",
        )
        k = next(j for j, s in enumerate(client.rx.states) if shows(s))
        out.append(client.rx.state_times[k] - t0)
        client.spin_for(0.3)  # past the command timeout: back to the profile
    return out


def _sustained(factor: float, check: dict) -> bool:
    """Within 2 % of the factor, with deadline misses on fewer than 1 % of the chunks."""
    return check["rtf"] >= 0.98 * factor and check["deadline_misses"] <= 0.01 * max(
        1, check["chunks"]
    )


@contextlib.contextmanager
def _node_and_client(
    scenario: str,
    measured: bool,
    domain_offset: int,
    exit_codes: list[int] | None = None,
    continuous: bool = False,
) -> Iterator[tuple[NodeProcess, SimClient]]:
    """A node running ``scenario`` at real-time factor 1 (for a day of simulated time, or
    without end with ``continuous``) and a client subscribed to every topic, on a private
    domain; both warmed up. Yields them; stops both on exit and appends the node's exit
    code to ``exit_codes``."""
    domain = domain_id_for(domain_offset)
    log = Path(tempfile.mkdtemp(prefix="brake_sim_bench_")) / "node.log"
    end = ["--continuous"] if continuous else ["--duration", "86400"]
    node = NodeProcess.start(
        ["--scenario", scenario, *end, "--ros-args", "-p",
         f"publish_measured:={'true' if measured else 'false'}"],
        domain_id=domain,
        log_path=log,
    )  # fmt: skip
    client = SimClient(domain, keep_chunks=False)
    try:
        client.wait_for_node(60.0)
        client.spin_for(WARM_UP_S)
        yield node, client
    finally:
        client.close()
        code = node.stop()
        if exit_codes is not None:
            exit_codes.append(code)


def _real_time_cpu(duration_s: float, scenario: str, measured: bool) -> dict[str, float]:
    """One node at real-time factor 1: its counters and CPU over ``duration_s``."""
    with _node_and_client(scenario, measured, 91) as (node, client):
        window = _Window(client, node.pid)
        client.spin_for(duration_s)
        return window.close()


def sensors_overhead(duration_s: float, scenario: str, rounds: int) -> str:
    """The node's extra CPU with ``publish_measured`` on, over alternated runs."""
    load_before = os.getloadavg()[0]
    cpu: dict[bool, list[float]] = {False: [], True: []}
    lines = [
        f"brake_sim node sensors overhead: scenario '{scenario}', {rounds} rounds of"
        f" {duration_s:g} s per setting at real-time factor 1, {os.cpu_count()} CPUs, load"
        f" average {load_before:.2f} before the start"
    ]
    for i in range(rounds):
        for measured in (False, True):
            r = _real_time_cpu(duration_s, scenario, measured)
            cpu[measured].append(r["cpu_pct"])
            lines.append(
                f"  round {i + 1}, sensors {'on ' if measured else 'off'}: CPU"
                f" {r['cpu_pct']:.1f} % of one core, real-time factor {r['rtf']:.4f},"
                f" deadline misses {r['deadline_misses']}, gaps {r['gaps']}"
            )
    off, on = statistics.mean(cpu[False]), statistics.mean(cpu[True])
    lines.append(
        f"  mean CPU: sensors off {off:.1f} %, on {on:.1f} % of one core; the sensors add"
        f" {100.0 * (on - off) / off:.1f} % to the node's CPU"
    )
    return "\n".join(lines)


def long_run(duration_s: float, scenario: str, report_every_s: float, measured: bool) -> int:
    """Print how a continuous node at real-time factor 1 holds up over ``duration_s``."""
    print(
        f"brake_sim continuous node: scenario '{scenario}', {duration_s:g} s at real-time"
        f" factor 1, sensors {'on' if measured else 'off'}, {os.cpu_count()} CPUs, load average"
        f" {os.getloadavg()[0]:.2f} before the start",
        flush=True,
    )
    print("wall (s) | simulated (s) | real-time factor | deadline misses | gaps | RSS (MB)")
    print("---|---|---|---|---|---")
    walls: list[float] = []
    rss: list[float] = []
    with _node_and_client(scenario, measured, 92, continuous=True) as (node, client):
        start = time.monotonic()
        while time.monotonic() - start < duration_s:
            window = _Window(client, node.pid)
            client.spin_for(min(report_every_s, duration_s - (time.monotonic() - start)))
            r = window.close()
            walls.append(time.monotonic() - start)
            rss.append(resident_mb(node.pid))
            sim_s = int(client.diagnostics()["sample_index"]) / float(
                client.diagnostics()["sample_rate_hz"]
            )
            print(
                f"{walls[-1]:.0f} | {sim_s:.1f} | {r['rtf']:.4f} | {r['deadline_misses']} |"
                f" {r['gaps']} | {rss[-1]:.1f}",
                flush=True,
            )
    if len(rss) >= 2:
        slope = statistics.linear_regression(walls, rss).slope * 3600.0
        print(
            f"resident memory: {rss[0]:.1f} MB at the first report, {rss[-1]:.1f} MB at the"
            f" last ({rss[-1] - rss[0]:+.1f} MB), slope {slope:+.2f} MB per hour"
        )
    return 0


def run(
    duration_s: float, scenario: str, afap_s: float, latency_count: int, measured: bool = True
) -> str:
    load_before = os.getloadavg()[0]  # other work on the machine skews every figure
    exit_codes: list[int] = []
    with _node_and_client(scenario, measured, 90, exit_codes) as (node, client):
        window = _Window(client, node.pid)
        client.spin_for(duration_s)
        rt = window.close()
        lat = _latency(client, latency_count)
        client.set_parameter("real_time_factor", 0.0)
        client.spin_for(1.0)
        window = _Window(client, node.pid)
        client.spin_for(afap_s)
        afap = window.close()
        checks = []
        for fraction in (0.8, 0.6, 0.4, 0.2):
            factor = max(1.0, math.floor(fraction * afap["rtf"]))
            client.set_parameter("real_time_factor", factor)
            client.spin_for(1.0)
            window = _Window(client, node.pid)
            client.spin_for(afap_s)
            check = window.close()
            checks.append((factor, check))
            if _sustained(factor, check) or factor == 1.0:
                break
    code = exit_codes[0]
    lat_ms = sorted(1e3 * x for x in lat)
    p95 = lat_ms[min(len(lat_ms) - 1, math.ceil(0.95 * len(lat_ms)) - 1)]
    lines = [
        f"brake_sim node benchmark: scenario '{scenario}', sensors (~/measured)"
        f" {'on' if measured else 'off'}, {os.cpu_count()} CPUs, load average"
        f" {load_before:.2f} before the start, node exit code {code}",
        f"  real-time factor 1 for {rt['wall_s']:.1f} s: CPU {rt['cpu_pct']:.1f} % of one core;"
        f" real-time factor {rt['rtf']:.4f}; deadline misses {rt['deadline_misses']}, slips"
        f" {rt['slips']}; samples received {rt['received']} of {rt['steps']}, gaps"
        f" {rt['gaps']}",
        f"  command-to-effect latency over {len(lat_ms)} commands: median"
        f" {statistics.median(lat_ms):.1f} ms, p95 {p95:.1f} ms, max {lat_ms[-1]:.1f} ms",
        f"  as fast as possible for {afap['wall_s']:.1f} s: real-time factor {afap['rtf']:.1f},"
        f" CPU {afap['cpu_pct']:.0f} %; client received {afap['received']} of"
        f" {afap['steps']} samples",
    ]
    for factor, check in checks:
        verdict = "sustained" if _sustained(factor, check) else "not sustained"
        lines.append(
            f"  real-time factor {factor:g} for {check['wall_s']:.1f} s: achieved"
            f" {check['rtf']:.2f}, deadline misses {check['deadline_misses']} of"
            f" {check['chunks']} chunks, slips {check['slips']}, CPU {check['cpu_pct']:.0f} %:"
            f" {verdict}"
        )
    best = max((f for f, c in checks if _sustained(f, c)), default=None)
    lines.append(
        "  highest sustained real-time factor with every topic published: "
        + (f"{best:g}" if best is not None else "below the last factor tried")
    )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = Parser(
        prog="python -m brake_sim_ros.studies.node_bench", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument(
        "--duration",
        type=float,
        default=60.0,
        metavar="S",
        help="wall seconds of the real-time run (default 60)",
    )
    parser.add_argument("--scenario", default="symmetric")
    parser.add_argument(
        "--afap-seconds",
        type=float,
        default=5.0,
        metavar="S",
        help="wall seconds of the as-fast-as-possible and check runs",
    )
    parser.add_argument("--latency-samples", type=int, default=20)
    parser.add_argument(
        "--no-measured",
        action="store_true",
        help="run the node with publish_measured:=false (no sensors, no ~/measured)",
    )
    parser.add_argument(
        "--sensors-overhead",
        type=int,
        default=0,
        metavar="ROUNDS",
        help="print only the sensors' extra CPU, from ROUNDS alternated pairs of runs",
    )
    parser.add_argument(
        "--long-run",
        type=float,
        default=0.0,
        metavar="S",
        help="print only how a continuous node holds up over S wall seconds (up to a day)",
    )
    parser.add_argument(
        "--report-every",
        type=float,
        default=60.0,
        metavar="S",
        help="with --long-run: wall seconds between reports (default 60)",
    )
    args = parser.parse_args(argv)
    # a benchmark stopped by SIGTERM (kill, a timeout) unwinds like Ctrl-C, so the node it
    # started (a continuous one runs without end) is stopped too
    signal.signal(signal.SIGTERM, lambda _signum, _frame: sys.exit(143))
    if not 0.0 <= args.long_run <= 86_400.0:
        parser.error(f"--long-run {args.long_run:g}: allowed > 0 to 86400 s")
    if not 1.0 <= args.report_every <= 3600.0:
        parser.error(f"--report-every {args.report_every:g}: allowed 1 to 3600 s")
    if args.long_run:
        return long_run(
            args.long_run, args.scenario, args.report_every, measured=not args.no_measured
        )
    if not 0 <= args.sensors_overhead <= 100:
        parser.error(f"--sensors-overhead {args.sensors_overhead}: allowed 1 to 100 rounds")
    if not 0.0 < args.duration <= 3600.0:
        parser.error(f"--duration {args.duration:g}: allowed > 0 to 3600 s")
    if args.sensors_overhead:
        print(sensors_overhead(args.duration, args.scenario, args.sensors_overhead), flush=True)
        return 0
    text = run(
        args.duration,
        args.scenario,
        args.afap_seconds,
        args.latency_samples,
        measured=not args.no_measured,
    )
    print(text, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
