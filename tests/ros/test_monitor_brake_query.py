""":class:`BrakeQuery`'s reading of the graph and of the answer, the cases a real node
cannot show here (a node older than the ``brake`` parameter, a nonsense value, a node
that never answers, a publisher whose node is not discovered yet, several publishers).
Pure logic: the graph, the client and the clock are stand-ins; the real exchange is
tests/ros/test_monitor_brake.py."""

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
    """The monitor's node: the graph and the clients it makes for other nodes."""

    publishers: list[Endpoint] = field(default_factory=list)
    clients: dict[str, Client] = field(default_factory=dict)
    destroyed: list[Client] = field(default_factory=list)

    def get_publishers_info_by_topic(self, topic: str) -> list[Endpoint]:
        assert topic == TOPIC
        return self.publishers

    def create_client(self, kind: type, service: str) -> Client:
        assert kind is GetParameters and service not in self.clients
        self.clients[service] = Client()
        return self.clients[service]

    def destroy_client(self, client: Client) -> None:
        self.destroyed.append(client)


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


def test_a_publisher_not_yet_named_is_waited_for_then_the_node_that_publishes_is_asked():
    graph, client, clock = Graph([Endpoint("_NODE_NAME_UNKNOWN_")]), Client(), Clock()
    query = _query(graph, client, clock)
    assert query.poll() is None and not graph.clients  # perhaps the simulator, not yet named
    graph.publishers[0] = Endpoint("brake_sim_replay", "/")  # brake-sim replay's node
    assert query.poll() is None
    replay = graph.clients["/brake_sim_replay/get_parameters"]
    assert replay.calls == [["brake"]] and not client.calls
    replay.future.response = _answer(
        ParameterValue(type=ParameterType.PARAMETER_STRING, string_value="study")
    )
    assert query.poll() == BrakeAnswer("study", source="/brake_sim_replay")
    assert graph.destroyed == [replay]  # the client made for it goes with the answer
    graph = Graph([Endpoint("driver", "/car")])
    query = _query(graph, Client(), Clock())
    assert query.poll() is None
    graph.clients["/car/driver/get_parameters"].future.response = _answer(
        ParameterValue(type=ParameterType.PARAMETER_NOT_SET)
    )
    answer = query.poll()
    assert answer is not None and answer.brake == ""
    assert "/car/driver, which publishes it, has no string parameter brake" in answer.why


def test_the_simulator_is_asked_among_publishers_and_several_others_are_not_asked():
    graph = Graph([Endpoint("brake_sim_replay"), Endpoint("brake_sim")])
    client = Client()
    assert _query(graph, client, Clock()).poll() is None
    assert client.calls == [["brake"]] and not graph.clients
    graph = Graph([Endpoint("brake_sim_replay"), Endpoint("brake_sim", "/other")])
    answer = _query(graph, Client(), Clock()).poll()
    assert answer is not None and answer.brake == "" and not graph.clients
    assert "published by /brake_sim_replay, /other/brake_sim: several nodes" in answer.why
