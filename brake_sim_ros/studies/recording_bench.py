"""Benchmark of MCAP recording: ``brake-sim bench recording [--scenario S] [--sim-seconds S]``.

Prints:
    * offline throughput: samples (physics samples, in PivotForceChunks) written per CPU
      second by ``record_offline`` (stepping included), with zstd and uncompressed, and the
      cost of the stream alone (stepping and message building, no file) for comparison;
    * size per simulated second, with zstd and uncompressed (MB/s of signal);
    * CPU of a node process at real-time factor 1 without and with ``--record``, in % of
      one core, from ``/proc/<pid>/stat`` over ``--node-seconds`` (default 15) of wall time
      after a warm-up, both measured in this one run (compare them with each other).
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

from brake_sim_ros import stream
from brake_sim_ros.command_line import Parser
from brake_sim_ros.recording.record import record_offline
from brake_sim_ros.recording.writer import RecordingOptions
from brake_sim_ros.ros.harness import NodeProcess, domain_id_for
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream.offline import offline_messages
from brake_sim_ros.studies.node_bench import cpu_seconds


def _stream_only(scenario, sim_s: float) -> tuple[float, int]:
    cpu0 = time.process_time()
    samples = 0
    for topic, msg, _ns in offline_messages(scenario, duration_s=sim_s):
        if topic is stream.PIVOT_FORCES:
            samples += len(msg.left_fx_n)
    return time.process_time() - cpu0, samples


def _node_cpu(scenario: str, seconds: float, record: Path | None, offset: int) -> float:
    args = ["--scenario", scenario, "--duration", "86400"]
    if record is not None:
        args += ["--record", str(record)]
    log = Path(tempfile.mkdtemp(prefix="brake_sim_bench_rec_")) / "node.log"
    node = NodeProcess.start(args, domain_id=domain_id_for(offset), log_path=log)
    try:
        end = time.monotonic() + 60.0
        while "samples per chunk" not in node.output():
            if time.monotonic() > end or node.proc.poll() is not None:
                raise RuntimeError(f"node did not start:\n{node.output()}")
            time.sleep(0.1)
        time.sleep(3.0)  # warm-up
        cpu0, wall0 = cpu_seconds(node.pid), time.monotonic()
        time.sleep(seconds)
        return 100.0 * (cpu_seconds(node.pid) - cpu0) / (time.monotonic() - wall0)
    finally:
        node.stop()


def run(scenario_name: str, sim_s: float, node_s: float) -> str:
    scenario = load_scenario(scenario_name)
    out = Path(tempfile.mkdtemp(prefix="brake_sim_bench_rec_"))
    list(offline_messages(scenario, duration_s=0.05))  # compile/load the kernel first
    lines = [
        f"recording benchmark: scenario '{scenario_name}', {sim_s:g} s simulated,"
        f" {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f}"
    ]
    base_cpu, samples = _stream_only(scenario, sim_s)
    lines.append(
        f"  stream only (no file): {samples / base_cpu:,.0f} samples/s CPU"
        f" ({sim_s / base_cpu:.1f}x real time)"
    )
    for compression in ("zstd", "none"):
        path = out / f"bench_{compression}.mcap"
        rec = record_offline(
            scenario,
            path,
            duration_s=sim_s,
            options=RecordingOptions(compression=compression, durable=False),
        )
        lines.append(
            f"  offline recording, {compression:4s}: {rec.samples / rec.cpu_s:,.0f} samples/s"
            f" CPU ({rec.sim_s / rec.cpu_s:.1f}x real time, recording adds"
            f" {1e6 * (rec.cpu_s - base_cpu) / rec.samples:.2f} µs CPU per sample);"
            f" {rec.size_bytes / 1e6 / rec.sim_s:.3f} MB per simulated second"
            f" ({rec.messages} messages, {rec.size_bytes / 1e6:.2f} MB)"
        )
    if node_s > 0:
        plain = _node_cpu(scenario_name, node_s, None, 70)
        recorded = _node_cpu(scenario_name, node_s, out / "node.mcap", 71)
        size = (out / "node.mcap").stat().st_size
        lines.append(
            f"  node at real-time factor 1 for {node_s:g} s: CPU {plain:.1f} % of one core"
            f" without recording, {recorded:.1f} % with --record (zstd, fsync every 1 s"
            f" simulated; file {size / 1e6:.2f} MB)"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="brake-sim bench recording", description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="symmetric")
    parser.add_argument("--sim-seconds", type=float, default=7.5, metavar="S")
    parser.add_argument(
        "--node-seconds",
        type=float,
        default=15.0,
        metavar="S",
        help="wall seconds per node CPU measurement (0: skip the node)",
    )
    args = parser.parse_args(argv)
    print(run(args.scenario, args.sim_seconds, args.node_seconds), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
