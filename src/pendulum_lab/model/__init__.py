"""The model layer: pendulums with their numbers bound, evaluated with NumPy.

``pendulum`` holds :class:`PendulumModel` (one system), :class:`ModelFamily` (many that differ
in some numbers), the factories and the checks of a model argument; ``numeric`` the functions
of a chain (lambdified, or looped for long chains) and of any system; ``angles`` the wrapping
of angles; ``system`` :class:`SystemModel`, the model of any mechanical system (and
:class:`SystemFamily`, many of them), and the
factories of the elastic, the Kapitza and the cart pendulum.
"""

from .angles import reduce_turns, wrap_angle
from .pendulum import (
    FAMILY_PARAMETERS,
    Drawing,
    ModelFamily,
    PendulumModel,
    double_pendulum,
    driven_pendulum,
    family_parameter,
    n_pendulum,
    require_chain,
    require_double_pendulum,
    require_model,
    simple_pendulum,
)
from .system import (
    SystemFamily,
    SystemModel,
    cart_pendulum,
    elastic_pendulum,
    foucault_pendulum,
    kapitza_pendulum,
    mechanical_system,
    spherical_pendulum,
)

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
