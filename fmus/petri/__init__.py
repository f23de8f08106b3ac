"""Petri-net FMUs: read a net (PNML or YAML), run it in Python, or compile it into an FMU model folder."""

from .compile import compile_net, write_model
from .interpreter import Interpreter
from .load import load_net, net_name
from .net import Net, Place, Transition
from .problems import NetError

__all__ = ["Interpreter", "Net", "NetError", "Place", "Transition", "compile_net", "load_net", "net_name",
           "write_model"]
