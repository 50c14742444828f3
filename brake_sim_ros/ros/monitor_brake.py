"""How the monitor learns which brake its stream comes from: it asks the node that
publishes it.

No message says which brake a MeasuredChunk comes from, and message definitions stay as
they are; the simulator node says it in its read-only ROS parameter ``brake`` (the running
scenario's, following a ``~/reset`` to a scenario of the other brake), and so does
``brake-sim replay``'s node (``brake_sim_replay``: the recording's brake).
:class:`BrakeQuery` asks once, with bounded waits, from the monitor's own executor (it
never blocks a callback): wait for a publisher of the measured topic (unbounded, as the
monitor waits for the stream itself), then, once one is seen, at most ``wait_s`` for the
answer of the node to ask: the simulator if it publishes the stream, else the one node
that does.

A stream whose publisher does not say its brake (a real brake's driver, a recording that
does not say it), or that several nodes but not the simulator publish, has no answer: it
then says why, and the monitor needs the brake declared (``--brake``).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from rcl_interfaces.msg import ParameterType
from rcl_interfaces.srv import GetParameters

from brake_sim_ros.model.parameters import BRAKES
from brake_sim_ros.ros.node_parameters import BRAKE

BRAKE_WAIT_S = 20.0  # from the stream's first publisher seen to the answer
# what rmw reports for an endpoint whose node it has not discovered yet
_UNKNOWN_NODE = "_NODE_NAME_UNKNOWN_"


@dataclass(frozen=True)
class BrakeAnswer:
    """What the query learnt: ``brake`` ("study" or "service") and the node that said it
    (``source``), or ``brake`` "" and ``why`` no node says it (one clause)."""

    brake: str
    source: str = ""
    why: str = ""


def _node_name(info: Any) -> str:
    """The fully qualified node name of a TopicEndpointInfo."""
    namespace = info.node_namespace.rstrip("/")
    return f"{namespace}/{info.node_name}"


class BrakeQuery:
    """One question, its parameter ``brake``, to the node that publishes ``topic``: the
    simulator if it does, else the one node that does.

    Args:
        node: the monitor's rclpy node (graph queries, the clients of other nodes).
        client: its GetParameters client of ``<simulator>/get_parameters``.
        simulator: the simulator's fully qualified node name.
        topic: the measured topic whose publishers are looked at.
        wait_s: the bounded wait (wall s) from the first publisher seen to the answer.
        clock: monotonic wall seconds.
    """

    def __init__(
        self,
        node: Any,
        client: Any,
        simulator: str,
        topic: str,
        *,
        wait_s: float = BRAKE_WAIT_S,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._node, self._simulator_client = node, client
        self._simulator, self._topic = simulator, topic
        self._wait_s, self._clock = wait_s, clock
        self._started: float | None = None
        self._asked = ""  # the node asked, once chosen
        self._client: Any = None
        self._future: Any = None

    def heard(self) -> None:
        """A message of the stream arrived: the bounded wait runs from now at the latest."""
        if self._started is None:
            self._started = self._clock()

    def poll(self) -> BrakeAnswer | None:
        """The answer, or None while it is still awaited."""
        names = {_node_name(i) for i in self._node.get_publishers_info_by_topic(self._topic)}
        if names:
            self.heard()
        if self._future is not None and self._future.done():
            return self._answer(self._future.result())
        if not self._asked:
            several = self._choose(names)
            if several is not None:
                return several
        if self._future is None and self._asked and self._client.service_is_ready():
            self._future = self._client.call_async(GetParameters.Request(names=[BRAKE.name]))
        if self._started is not None and self._clock() - self._started > self._wait_s:
            publishers = f"publishers: {', '.join(sorted(names))}" if names else "none seen"
            asked = self._asked or f"no single node ({publishers})"
            return self._close(
                BrakeAnswer(
                    "",
                    why=f"{asked[:200]} did not say its brake (its parameter {BRAKE.name})"
                    f" within {self._wait_s:g} s of the stream",
                )
            )
        return None

    def _choose(self, names: set[str]) -> BrakeAnswer | None:
        """Pick the node to ask among the stream's publishers ``names``, once every one is
        known by name; an answer (none to ask) when several publish it, none the simulator."""
        known = {n for n in names if not n.endswith("/" + _UNKNOWN_NODE)}
        if self._simulator in names:
            self._asked, self._client = self._simulator, self._simulator_client
        elif known and known == names and len(known) == 1:
            (self._asked,) = known
            self._client = self._node.create_client(GetParameters, f"{self._asked}/get_parameters")
        elif known and known == names:
            return BrakeAnswer(
                "",
                why=f"published by {', '.join(sorted(names))[:200]}: several nodes, none the"
                f" simulator {self._simulator}, so none is asked its brake",
            )
        return None

    def _answer(self, response: Any) -> BrakeAnswer:
        values = list(getattr(response, "values", None) or [])
        value = values[0] if len(values) == 1 else None
        if value is None or value.type != ParameterType.PARAMETER_STRING:
            return self._close(
                BrakeAnswer(
                    "",
                    why=f"{self._asked}, which publishes it, has no string parameter"
                    f" {BRAKE.name} (a driver, or a node older than this monitor)",
                )
            )
        brake = value.string_value
        if brake not in BRAKES:
            return self._close(
                BrakeAnswer(
                    "",
                    why=f"{self._asked} says brake {brake[:40]!r}, not one of {', '.join(BRAKES)}",
                )
            )
        return self._close(BrakeAnswer(brake, source=self._asked))

    def _close(self, answer: BrakeAnswer) -> BrakeAnswer:
        """The client this query made for a node not the simulator is destroyed."""
        if self._client is not None and self._client is not self._simulator_client:
            self._node.destroy_client(self._client)
        self._client = None
        return answer


class StreamBrake:
    """The brake half of :class:`~brake_sim_ros.ros.monitor.MonitorNode` (a mixin of that
    one class): it asks, and judges the held samples with the answer or refuses them."""

    def _ask_brake(self) -> None:
        self._brake_query = BrakeQuery(self, self._parameters, self.simulator, self.measured_topic)
        self.get_logger().info(
            f"asking the node that publishes {self.measured_topic} ({self.simulator} if it"
            " does; its parameter brake) which brake the stream comes from; its samples are"
            " held until it says"
        )

    def _poll_brake(self) -> None:
        if self._brake_query is None or self.refusal is not None:
            return
        answer = self._brake_query.poll()
        if answer is not None:
            self._brake_query = None
            self._settle_brake(answer)

    def _settle_brake(self, answer: BrakeAnswer) -> None:
        """Judge the held samples with the brake learnt, or refuse them (one line)."""
        where = f"the stream on {self.measured_topic}"
        if answer.brake and self.brake and answer.brake != self.brake:
            refusal: str | None = (
                f"the brake declared for {where} is the {self.brake} brake (--brake, the ROS"
                f" parameter brake), but {answer.source} says the {answer.brake} brake"
                f" (its parameter brake): allowed --brake {answer.brake}, or none (the"
                " monitor asks the node that publishes the stream)"
            )
        elif answer.brake:
            refusal = self.detector.brake_refusal(
                answer.brake, f"{where}, as {answer.source} says,"
            )
        elif self.brake:
            refusal = None
            self._asks_brake = False  # no node says it: the declared brake holds
            self.get_logger().info(f"{answer.why}; judging it as the declared {self.brake} brake")
        else:
            refusal = self.detector.brake_refusal("", f"{where} ({answer.why})")
        if refusal is not None:
            self.refusal = refusal
            self._held.clear()
            self.get_logger().error(refusal)
            return
        if answer.brake and answer.brake != self.stream_brake:
            self.get_logger().info(f"{answer.source} says the {answer.brake} brake")
        self.stream_brake = answer.brake
        held, self._held = self._held, []
        for msg in held:
            if self.refusal is None:
                self._judge(msg)
