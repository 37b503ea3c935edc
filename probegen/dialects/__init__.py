"""IR → program text, one module per controller (``get_dialect(name)``)."""

from probegen.dialects.base import REGISTRY, Dialect, get_dialect
from probegen.dialects.dmis import Dmis
from probegen.dialects.fanuc import Fanuc
from probegen.dialects.haas import Haas
from probegen.dialects.linuxcnc import LinuxCnc

__all__ = ["REGISTRY", "Dialect", "Dmis", "Fanuc", "Haas", "LinuxCnc", "get_dialect"]
