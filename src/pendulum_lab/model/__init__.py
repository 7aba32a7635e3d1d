"""The model layer: pendulums with their numbers bound, evaluated with NumPy.

``pendulum`` holds :class:`PendulumModel` (one chain), :class:`ModelFamily` (many that differ
in some numbers) and the checks of a model argument; ``functions`` the numeric methods every
model shares; ``chains`` the factories of chains; ``drawing`` what a picture of a model shows;
``family`` what every family shares; ``parameters`` the numbers a chain accepts; ``numeric``
the functions of a chain (lambdified, or looped for long chains) and of any system; ``angles``
the wrapping of angles; ``system`` :class:`SystemModel`, the model of any mechanical system
(and :class:`SystemFamily`, many of them); ``named_systems`` the factories of the elastic, the
Kapitza, the cart, the spherical and the Foucault pendulum.
"""

from .angles import reduce_turns, wrap_angle
from .chains import double_pendulum, driven_pendulum, n_pendulum, simple_pendulum
from .named_systems import (
    cart_pendulum,
    elastic_pendulum,
    foucault_pendulum,
    kapitza_pendulum,
    spherical_pendulum,
)
from .pendulum import (
    FAMILY_PARAMETERS,
    Drawing,
    ModelFamily,
    PendulumModel,
    family_parameter,
    require_chain,
    require_double_pendulum,
    require_model,
)
from .system import SystemFamily, SystemModel, mechanical_system

__all__ = [
    "Drawing",
    "FAMILY_PARAMETERS",
    "ModelFamily",
    "PendulumModel",
    "SystemFamily",
    "SystemModel",
    "cart_pendulum",
    "elastic_pendulum",
    "foucault_pendulum",
    "kapitza_pendulum",
    "mechanical_system",
    "spherical_pendulum",
    "double_pendulum",
    "driven_pendulum",
    "family_parameter",
    "n_pendulum",
    "reduce_turns",
    "require_chain",
    "require_double_pendulum",
    "require_model",
    "simple_pendulum",
    "wrap_angle",
]
