""":class:`BrakeQuery`'s reading of the graph and of the answer, the cases a real node
cannot show here (a node older than the ``brake`` parameter, a nonsense value, a node
that never answers, a publisher whose node is not discovered yet). Pure logic: the graph,
the client and the clock are stand-ins; the real exchange is tests/ros/test_monitor_brake.py.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rcl_interfaces.msg import ParameterType, ParameterValue
from rcl_interfaces.srv import GetParameters

from brake_sim_ros.ros.monitor_brake import BrakeAnswer, BrakeQuery

SIM = "/brake_sim"
TOPIC = "/brake_sim/measured"


@dataclass
class Endpoint:
    node_name: str
    node_namespace: str = "/"


@dataclass
class Graph:
    publishers: list[Endpoint] = field(default_factory=list)

    def get_publishers_info_by_topic(self, topic: str) -> list[Endpoint]:
        assert topic == TOPIC
        return self.publishers


class Future:
    def __init__(self) -> None:
        self.response: GetParameters.Response | None = None

    def done(self) -> bool:
        return self.response is not None

    def result(self) -> GetParameters.Response | None:
        return self.response


@dataclass
class Client:
    ready: bool = True
    calls: list[list[str]] = field(default_factory=list)
    future: Future = field(default_factory=Future)

    def service_is_ready(self) -> bool:
        return self.ready

    def call_async(self, request: GetParameters.Request) -> Future:
        self.calls.append(list(request.names))
        return self.future


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def _query(graph: Graph, client: Client, clock: Clock) -> BrakeQuery:
    return BrakeQuery(graph, client, SIM, TOPIC, wait_s=20.0, clock=clock)


def _answer(value: ParameterValue) -> GetParameters.Response:
    return GetParameters.Response(values=[value])


def test_it_waits_for_the_stream_without_bound_then_asks_once_and_reads_the_brake():
    graph, client, clock = Graph(), Client(), Clock()
    query = _query(graph, client, clock)
    clock.now += 1000.0
    assert query.poll() is None and not client.calls  # no publisher yet: no clock runs
    graph.publishers.append(Endpoint("brake_sim"))
    assert query.poll() is None and client.calls == [["brake"]]
    assert query.poll() is None and len(client.calls) == 1  # asked once
    client.future.response = _answer(
        ParameterValue(type=ParameterType.PARAMETER_STRING, string_value="service")
    )
    assert query.poll() == BrakeAnswer("service", source=SIM)


def test_a_node_without_the_parameter_or_with_another_value_says_no_brake():
    for value, words in [
        (ParameterValue(type=ParameterType.PARAMETER_NOT_SET), "no string parameter brake"),
        (ParameterValue(type=ParameterType.PARAMETER_STRING, string_value="disc"), "'disc'"),
    ]:
        graph, client, clock = Graph([Endpoint("brake_sim")]), Client(), Clock()
        query = _query(graph, client, clock)
        assert query.poll() is None
        client.future.response = _answer(value)
        answer = query.poll()
        assert answer is not None and answer.brake == "" and words in answer.why


def test_an_answer_that_does_not_come_is_waited_for_20_s_from_the_stream():
    graph, client, clock = Graph(), Client(ready=False), Clock()
    query = _query(graph, client, clock)
    query.heard()  # a message arrived before the graph showed its publisher
    graph.publishers.append(Endpoint("brake_sim"))
    clock.now += 19.9
    assert query.poll() is None
    clock.now += 0.2
    answer = query.poll()
    assert answer is not None and answer.brake == ""
    assert "did not say its brake (its parameter brake) within 20 s" in answer.why


def test_a_publisher_not_yet_named_is_waited_for_and_another_node_says_no_brake():
    graph, client, clock = Graph([Endpoint("_NODE_NAME_UNKNOWN_")]), Client(), Clock()
    query = _query(graph, client, clock)
    assert query.poll() is None  # perhaps the simulator, not yet discovered by name
    graph.publishers[0] = Endpoint("brake_sim_replay", "/")
    answer = query.poll()
    assert answer is not None and answer.brake == "" and not client.calls
    assert "published by /brake_sim_replay, not by the simulator /brake_sim" in answer.why
    graph = Graph([Endpoint("brake_sim", "/other")])
    answer = _query(graph, Client(), Clock()).poll()
    assert answer is not None and "published by /other/brake_sim" in answer.why
