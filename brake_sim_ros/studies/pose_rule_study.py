"""The pose-rule study's command (issue 28, case 1): the rules of
:mod:`brake_sim_ros.studies.pose_rules` compared at the parameters in force (the study
brake's), a random sample of the calibration's space (:mod:`.pose_rule_sample`; it found
the study brake's geometry) and the validation's checks under each rule
(:mod:`.pose_rule_validation`).

Run it with ``python -m brake_sim_ros.studies.pose_rule_study`` (seconds; ``--help``).
"""

from __future__ import annotations

from brake_sim_ros.command_line import Parser
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.studies import pose_rules
from brake_sim_ros.studies.pose_rule_sample import (
    grid_point,
    print_sample,
    sample_geometries,
    sample_rule,
    scenario_check,
    verify,
)
from brake_sim_ros.studies.pose_rule_validation import print_validation
from brake_sim_ros.studies.pose_rules import RULES, report_rule


def main(argv: list[str] | None = None) -> int:
    parser = Parser(description=pose_rules.__doc__.splitlines()[0])
    parser.add_argument("--rules", nargs="*", default=list(RULES), choices=list(RULES))
    parser.add_argument("--crown-mm", nargs="*", type=float, default=[0.0])
    parser.add_argument("--pcts", nargs="*", type=float, default=[-3.0, 3.0])
    parser.add_argument(
        "--verify", action="store_true", help="the calibration's figures of the parameters in force"
    )
    parser.add_argument(
        "--validate",
        nargs="+",
        default=[],
        choices=list(RULES),
        help="the validation's checks with the pins placed by these rules",
    )
    parser.add_argument(
        "--sample", type=int, default=0, help="random geometries per rule (0: none)"
    )
    args = parser.parse_args(argv)
    params = BrakeParameters()
    if args.validate:
        for name in args.validate:
            print_validation(params, name)
        return 0
    if args.verify:
        point = grid_point(params, params.shoe.pose, 0.0, (0.0, 0.0, 0.0))
        cells = "  ".join(f"{k} {m:+.2f}" for k, m in point.misses.items())
        print(f"{params.shoe.pose}: misses in band units: {cells}")
        print("\n".join(verify(point)))
        print("\n".join(scenario_check(params, params.shoe.pose)))
        return 0
    if args.sample:
        geometries = sample_geometries(params, args.sample)
        print(
            f"{len(geometries)} of {args.sample} random geometries of the calibration's space"
            " have the symmetric first impact and case 5 in their bands"
        )
        for name in args.rules:
            sample = sample_rule(name, geometries)
            print_sample(sample)
            for point in sample.case1_inside():
                print("   case 1 in its bands: " + "\n   ".join(verify(point)))
        return 0
    for crown in args.crown_mm:
        for name in args.rules:
            report_rule(params, name, crown, sorted(args.pcts))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
