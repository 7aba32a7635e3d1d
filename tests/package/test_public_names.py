"""The public names of pendulum_lab before it was layered still resolve after it.

The surface below was read from the package as it was (every name of ``pendulum_lab`` and of each
public module), less three names that the layering removed on purpose and the changelog lists:
``codegen.package_files`` (cache keys are found from the code now) and ``loops.compiled_loop``,
``loops.new_memory`` (replaced by ``loops.compile_method`` and its ``CompiledMethod``).
"""

import pytest

import pendulum_lab as pl

SURFACE = {
    "pl": (
        "CONFORMAL_METHODS", "Chain", "ConvergenceError", "METHODS", "Method", "ModelFamily",
        "PendulumModel", "SegmentedRun", "Trajectory", "VARIATIONAL_METHODS", "codegen",
        "derive_chain", "discrete_mechanics", "double_pendulum", "driven_pendulum", "family",
        "get_method", "hamiltonian_field", "henon", "henon_step", "integrators", "loops",
        "mechanics", "model", "modified_hamiltonian", "n_pendulum", "segments", "simple_pendulum",
        "simulate", "simulate_segments", "step", "step_count", "tableau", "warm_up",
    ),
    "analysis": (
        "AdaptiveRun", "ComparisonRow", "EnergyComparison", "EnergyDecay", "HIGH_ORDER_DTS",
        "LinearDecay", "MethodComparison", "ORDER_DTS", "OrderResult", "SCIPY_METHODS",
        "StageIteration", "WorkPrecision", "amplification", "compare_energy", "compare_methods",
        "compare_trajectory", "dominant_frequencies", "dop853_work_precision", "energy_decay",
        "energy_growth", "equilibrium_angles", "exact_period", "find_equilibrium",
        "finite_difference_jacobian", "global_error", "linear_decay", "linearized_solution",
        "normal_mode_frequencies", "normal_modes", "observed_order", "order_steps",
        "oscillation_period", "pendulum_name", "reference_solution", "rest_state_at_energy",
        "reversibility_error", "scipy_run", "spectrum", "stability_limit", "stage_contraction",
        "step_jacobian", "symplectic_form_defect", "symplecticity_defect", "windowed_energy_error",
        "work_precision",
    ),
    "animation": (
        "EXPORT_SIZE", "FPS", "MAX_FRAMES", "PendulumScene", "RUN_COLOURS", "SPEEDS", "Simulator",
        "TRAIL", "count_frames", "encode_frame", "frame_indices", "html_animation",
        "save_animation", "scene_runs", "simulator", "still_frame",
    ),
    "chaos": (
        "Basins", "BifurcationDiagram", "EnergyExponent", "EnergyLyapunov", "FlipMap", "LANDINGS",
        "LandingErrors", "LyapunovEstimate", "LyapunovSpectrum", "PeriodDoubling", "PeriodWindow",
        "PoincareSection", "REGULAR_BELOW", "Separation", "SmallAngleComparison",
        "StroboscopicSection", "basins_of_attraction", "bifurcation_diagram", "can_flip",
        "energy_sections", "flip_time_map", "landing_errors", "lyapunov_benettin",
        "lyapunov_by_energy", "lyapunov_spectrum", "lyapunov_variational", "orbit_periods",
        "poincare_section", "section_spread", "section_states", "separation", "separation_between",
        "small_angle_comparison", "stroboscopic_section",
    ),
    "geometric": (
        "ModifiedEnergy", "STEP_SIZE", "modified_energy", "modified_equation",
        "modified_hamiltonian",
    ),
    "plotting": (
        "KINETIC", "LIBRATION", "PANELS", "POTENTIAL", "QUANTITIES", "ROTATION", "SEPARATRIX",
        "TOTAL", "axis_label", "draw_pendulum", "drawing_frame", "get_axes", "get_axes_grid",
        "link_label", "new_figure", "plot_adaptive_energy", "plot_amplification", "plot_angles",
        "plot_area_ratio", "plot_basins", "plot_bifurcation", "plot_carried_loops", "plot_energy",
        "plot_energy_comparison", "plot_energy_decay", "plot_energy_drift", "plot_energy_error",
        "plot_energy_error_growth", "plot_error_growth", "plot_flip_map", "plot_landing_errors",
        "plot_level_sets", "plot_linear_vs_nonlinear", "plot_link_projections", "plot_lyapunov",
        "plot_lyapunov_energy", "plot_lyapunov_spectrum", "plot_modified_energy_orders",
        "plot_modified_level_sets", "plot_normal_modes", "plot_orbit_on_level_sets", "plot_order",
        "plot_parting", "plot_period_vs_amplitude", "plot_phase", "plot_phase_portrait",
        "plot_projected_areas", "plot_section", "plot_sections", "plot_separation",
        "plot_small_angle", "plot_spectrum", "plot_stage_contraction", "plot_standard_map",
        "plot_step_sizes", "plot_stroboscopic", "plot_transport_threshold", "plot_work_precision",
        "subscript", "wrap_angle",
    ),
    "widgets": (
        "DT_CHOICES", "EnergyExplorer", "EquilibriumExplorer", "Explorer", "Instrument",
        "LiveSimulator", "MAX_STEPS", "PortraitExplorer", "SectionExplorer", "explore",
        "explore_energy", "explore_equilibrium", "live_simulator", "portrait_explorer",
        "section_explorer", "section_reach", "separation_panel",
    ),
    "cluster": (
        "check_client", "map_members", "members_of", "portable_method",
    ),
    "codegen": (
        "discrete_kernel_source", "import_name", "kernel_source", "load_discrete_kernels",
        "load_generated", "load_kernels", "looped_kernels", "paired_trig", "parameters_array",
        "sincos", "solve_spd", "stage_kernel",
    ),
    "discrete_mechanics": (
        "DiscreteLagrangian", "RULES", "discrete_lagrangian", "discrete_momenta", "reference_step",
    ),
    "events": (
        "Crossings", "check_direction", "find_crossings", "hermite", "hermite_slope", "land",
    ),
    "long_chains": (
        "LoopedChain", "acceleration", "hamilton", "link_sums", "solve_mass",
    ),
    "mechanics": (
        "Chain", "Equilibrium", "LIMITS", "LagrangianDerivation", "derive_chain",
        "is_identically_zero", "lagrangian_derivation",
    ),
    "report": (
        "DEFAULT_DT", "DEFAULT_T_END", "PENDULUMS", "QUICK_T_END", "ReportResult", "add_arguments",
        "add_report_command", "build_parser", "main", "run_from_args", "run_report",
        "settings_from_args",
    ),
    "source": (
        "method_source",
    ),
    "tables": (
        "COMPARISON_COLUMNS", "markdown_table",
    ),
    "timing": (
        "ChainCost", "FirstUseCost", "chain_costs", "first_use_cost",
    ),
    "warmup": (
        "warm_up",
    ),
    "segments": (
        "SegmentedRun", "default_segment_steps", "segment_length", "simulate_segments",
    ),
    "integrators": (
        "ButcherTableau", "CONFORMAL_METHODS", "ConvergenceError", "HamiltonianField", "METHODS",
        "Method", "Step", "VARIATIONAL_METHODS", "explicit_rk", "fixed_point_status",
        "gauss_legendre_tableau", "get_method", "implicit_kick", "implicit_rk", "jit_step",
        "kernel_function", "remove_damping", "step_kernels", "suitable_methods", "tableau_step",
        "unsuitability", "variational_method", "variational_step",
    ),
    "model": (
        "PendulumModel", "double_pendulum", "driven_pendulum", "n_pendulum", "simple_pendulum",
    ),
    "family": (
        "FAMILY_PARAMETERS", "ModelFamily",
    ),
    "loops": (
        "CALLS", "NOT_CONVERGED", "NOT_FINITE", "RUNNING", "STATUS", "STEPS", "SWEEPS",
        "loop_source", "time_loop",
    ),
    "tableau": (
        "ButcherTableau", "Condition", "gauss_legendre_tableau", "rooted_trees",
    ),
}


@pytest.mark.parametrize("module", sorted(SURFACE))
def test_every_public_name_of_before_still_resolves(module):
    owner = pl if module == "pl" else getattr(pl, module)
    missing = [name for name in SURFACE[module] if not hasattr(owner, name)]
    assert missing == []


def test_a_name_that_never_existed_is_an_attribute_error():
    # negative control: the lookup is not satisfied by anything at all
    with pytest.raises(AttributeError):
        pl.no_such_module  # noqa: B018


#: Names added since the layering, with the module that holds each.
ADDED = {
    "pl": ("MechanicalSystem", "SystemModel", "cart_pendulum", "elastic_pendulum",
           "kapitza_pendulum", "mechanical_system", "method_source"),
    "model": ("SystemModel", "cart_pendulum", "elastic_pendulum", "kapitza_pendulum",
              "mechanical_system"),
    "codegen": ("load_system_kernels",),
    "symbolic": ("MechanicalSystem",),
}


@pytest.mark.parametrize("module", sorted(ADDED))
def test_every_added_public_name_resolves_and_is_exported(module):
    owner = pl if module == "pl" else getattr(pl, module)
    assert [name for name in ADDED[module] if not hasattr(owner, name)] == []
    exported = getattr(owner, "__all__", None)
    if module == "pl" or exported is not None:
        assert set(ADDED[module]) <= set(exported)
