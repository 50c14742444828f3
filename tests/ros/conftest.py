"""What every test of this folder shares: rclpy and the built interfaces, the ``ros``
marker, and a brake_sim node in its own process with a client over real DDS.

Without rclpy or the built ``brake_sim_msgs`` (``scripts/setup.sh`` builds them) the whole
folder is skipped with one line saying which import failed; every test here needs them.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

import pytest

try:
    import brake_sim_msgs.msg  # noqa: F401
    import rclpy  # noqa: F401
except ImportError as error:  # pragma: no cover - a machine without ROS
    pytest.skip(
        f"rclpy or brake_sim_msgs not importable ({error}): run scripts/setup.sh",
        allow_module_level=True,
    )

from rclpy.qos import QoSProfile, ReliabilityPolicy

from brake_sim_ros.ros import qos
from brake_sim_ros.ros.harness import NodeProcess, SimClient, deep_history_args
from tests import cli_process

HERE = Path(__file__).parent
# lark (pulled in by rclpy's type-description code) imports sre_parse
SRE_WARNING = "ignore:module 'sre_(parse|constants)' is deprecated"


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Every test of this folder needs rclpy and the interfaces (marker ``ros``)."""
    for item in items:
        if HERE in item.path.parents:
            item.add_marker(pytest.mark.ros)
            item.add_marker(pytest.mark.filterwarnings(SRE_WARNING))


class Nodes:
    """Start brake_sim nodes, each in its own process, logging to a fresh temporary folder
    unless told where (``log_path``); ``python``: the interpreter (default this one)."""

    def __init__(self, tmp_path_factory: pytest.TempPathFactory) -> None:
        self._tmp = tmp_path_factory

    def _start(self, args: list[str], domain: int, log_path: Path | None, python: str | None):
        log = log_path or self._tmp.mktemp("node") / "node.log"
        extra = {"python": python} if python else {}
        return NodeProcess.start(
            args, domain_id=domain, log_path=log, launch=cli_process.popen, **extra
        )

    @contextlib.contextmanager
    def process(
        self,
        args: list[str],
        domain: int,
        *,
        log_path: Path | None = None,
        python: str | None = None,
        exit_code: int | None = 0,
    ) -> Iterator[NodeProcess]:
        """A node started with ``args`` on ``domain`` for the block; stopped at its end
        (SIGINT), when it must exit with ``exit_code`` (None: not checked, e.g. after the
        block killed it)."""
        node = self._start(args, domain, log_path, python)
        try:
            yield node
        finally:
            code = node.stop()
            if exit_code is not None:
                assert code == exit_code, node.output()

    @contextlib.contextmanager
    def with_client(
        self,
        args: list[str],
        domain: int,
        *,
        stream_qos: QoSProfile = qos.STREAM_CONSUMER,
        wait_s: float = 60.0,
        **process: object,
    ) -> Iterator[tuple[NodeProcess, SimClient]]:
        """:meth:`process`, and a :class:`SimClient` (``stream_qos``) that has discovered
        the node within ``wait_s`` seconds; closed before the node stops. A reliable
        ``stream_qos`` (a lossless check) gets the node's deep histories too."""
        if stream_qos.reliability is ReliabilityPolicy.RELIABLE:
            args = [*args, *deep_history_args(measured="publish_measured:=true" in args)]
        with self.process(args, domain, **process) as node:
            client = SimClient(domain, stream_qos=stream_qos)
            try:
                client.wait_for_node(wait_s)
                yield node, client
            finally:
                client.close()

    def run(
        self,
        args: list[str],
        domain: int,
        *,
        timeout_s: float = 60.0,
        log_path: Path | None = None,
        python: str | None = None,
    ) -> tuple[int, str]:
        """A node run that ends by itself (``--exit-at-end``, or refused at start), waited
        for at most ``timeout_s``: its exit code and its whole output."""
        node = self._start(args, domain, log_path, python)
        try:
            code = node.wait(timeout_s)
        finally:
            node.stop()
        return code, node.output()


@pytest.fixture(scope="session")
def nodes(tmp_path_factory: pytest.TempPathFactory) -> Nodes:
    """Session-scoped, so that a module fixture can share one node across a file's tests."""
    return Nodes(tmp_path_factory)


@pytest.fixture(scope="session")
def node_and_client(nodes: Nodes):
    """``with node_and_client(args, domain) as (node, client):`` (:meth:`Nodes.with_client`)."""
    return nodes.with_client
