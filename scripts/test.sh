#!/usr/bin/env bash
# Runs the whole test suite on lavapipe with the Khronos validation layer on (any validation
# message fails a test), after installing what is missing. Extra arguments go to `cargo test`.
#
# Without arguments, the GPU tests then run once more the way a discrete GPU runs them
# (docs/DESIGN.md "Staging" and "Subgroup widths"): IRAD_FORCE_STAGING=1 puts every buffer
# behind staging copies (device-local memory the host cannot map), and
# LP_NATIVE_VECTOR_WIDTH=128 makes lavapipe's subgroups 4 lanes wide instead of 8, so the
# staging path and the subgroup-width-dependent kernels (scans, env and luminaire tables, bir's
# resampling) run at both widths.
#
# That pass leaves out the long statistical tests listed below, each a mean or an error of many
# renders against a reference. lavapipe renders the same bits staged and at 4 lanes: measured
# when this list was made, every statistic those tests print (95 lines) came out the same to
# the last digit in both passes, so in the second pass they only recomputed the first pass's
# numbers. What they could find there, a kernel that goes wrong staged or at 4 lanes,
# tests/pixel_hashes.rs finds for each of their configurations (strategies, clamps,
# absorption, interleaving, alpha, shared samples, bundle directions, glossy suppression),
# rendered at 24 x 16 with their bits checked exactly against the recorded ones in both
# passes. Every test of a table, a scan, a sampler's pdf, a readback or a kernel's structure
# stays in the second pass, as do the cheaper statistical tests (the luminaire near its image
# plane, the closed-form disk, the moving-sun map, the two-bounce clamp, roulette over
# lights). compensation.rs is left out whole: its one test renders ir and bir at their
# default compensated clamp and ir at the plain clamp on the corner light, pixel_hashes cases.
SECOND_PASS_SKIPS=(
  # bir.rs: strategies standard, reverse, both, resampled and not; reverse and both unclamped
  # in the halogen office; the uniform floor on and off (a CDF parameter).
  every_strategy_matches_the_reference_mean_in_the_cornell_box
  both_sides_beat_reverse_only_in_the_halogen_office
  the_uniform_floor_keeps_the_mean_where_power_estimates_miss_vpls
  # ir.rs: roulette absorption unclamped, interleaving k = 4, VPL direct light clamped plain.
  fractional_and_roulette_absorption_match_the_reference
  ir_mean_matches_the_reference_with_and_without_interleaving
  error_falls_with_vpls_and_clamping_darkens_corners
  # env.rs: every strategy, light samples only, shared samples.
  every_strategy_matches_the_reference_direct_light
  decorrelated_light_samples_keep_the_image_mean_within_its_standard_error
  dynamic_shares_waste_fewer_samples_with_the_sun_behind
  uniform_faces_needs_more_samples_at_equal_error
  # lightfield.rs: brute force, uniform, precomputed, restricted with shared Halton points.
  every_lightfield_strategy_matches_the_brute_force
  strategies_at_equal_error
  # reference.rs: alpha's direct light (max_depth 1, alpha_frames).
  alpha_direct_light_is_unbiased_and_lowers_the_variance
  # light_bvh.rs: the path tracer by power and by the light BVH (the mirror test stays).
  path_tracer_is_unbiased_with_either_sampler
  # bundles.rs: strategies vpl, bundle, mis, two-bounce; environment and uniform directions;
  # glossy suppression none, roughness, clamp.
  every_strategy_matches_the_path_length_limited_reference_mean
  environment_bundles_match_the_reference_direct_light
  mis_beats_vpls_and_bundles_alone_in_the_corner
  roughness_clamping_suppresses_glossy_spikes_and_keeps_more_energy_than_clamping
  # state_across_frames.rs: env, bundles and restir on a map sequence (restir's temporal reuse
  # across a change of map is a pixel-hash case on moving-sun).
  every_method_that_renders_a_map_follows_a_sequence_that_dims_turns_and_brightens
)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo test --locked "$@"
if [ "$#" -eq 0 ]; then
  echo "== the GPU tests again, staged buffers and 4-lane subgroups"
  skips=()
  for t in "${SECOND_PASS_SKIPS[@]}"; do skips+=(--skip "$t"); done
  IRAD_FORCE_STAGING=1 LP_NATIVE_VECTOR_WIDTH=128 cargo test --locked \
    --test prefix_sum --test bvh --test buffers --test reference --test ir --test bir \
    --test bundles --test env --test lightfield --test tables --test pixel_hashes \
    --test custom_method --test light_bvh \
    -- --exact "${skips[@]}"
fi
