"""Command line: python -m petri compile NET MODEL_DIR | check NET... (run from fmus/, as fmus/Makefile does)."""

import argparse
import sys

from .compile import compile_net
from .load import load_net
from .problems import NetError


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m petri", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    compile_ = commands.add_parser("compile", help="write MODEL_DIR/model.yaml and model.c for the net")
    compile_.add_argument("net", help="a *.pnml or *.net.yaml file")
    compile_.add_argument("model_dir", help="output folder, named after the net")
    check = commands.add_parser("check", help="report every problem of the nets")
    check.add_argument("nets", nargs="+")
    args = parser.parse_args(argv)
    problems = []
    if args.command == "compile":
        try:
            compile_net(args.net, args.model_dir)
        except NetError as error:
            problems += error.problems
        except ValueError as error:  # a model folder not named after the net
            problems.append(str(error))
    else:
        for path in args.nets:
            try:
                load_net(path)
            except NetError as error:
                problems += error.problems
    if problems:
        print("\n".join(problems), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
