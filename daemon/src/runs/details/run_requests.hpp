#pragma once
// The parameters of each run command's request, one table each (key, type, range): the command
// table's rows point at them (service/details/command_table.cpp), the run builders read the keys
// they share through them, and docs/reference/protocol.md lists them (protocol_reference_test
// holds the page to these tables). A key two requests share is defined once here. Ranges that
// depend on the bench (frequency_hz up to a twentieth of the loop rate, identify's u_min/u_max
// within the output limits) are checked by the run builders on top of these.
#include <array>
#include <cstddef>
#include <utility>

#include "runs/details/request_params.hpp"

namespace hystbench::daemon::details {

namespace request_fields {

using T = ParamType;

inline constexpr double kWeekS = 7.0 * 24 * 3600;

/// The tables given, one after the other.
template <std::size_t N, std::size_t M>
constexpr std::array<ParamSpec, N + M> join(const std::array<ParamSpec, N>& a,
                                            const std::array<ParamSpec, M>& b) {
  return [&]<std::size_t... I, std::size_t... J>(std::index_sequence<I...>,
                                                 std::index_sequence<J...>) {
    return std::array<ParamSpec, N + M>{a[I]..., b[J]...};
  }
  (std::make_index_sequence<N>{}, std::make_index_sequence<M>{});
}
template <std::size_t N, std::size_t M, typename... More>
constexpr auto join(const std::array<ParamSpec, N>& a, const std::array<ParamSpec, M>& b,
                    const More&... more) {
  return join(join(a, b), more...);
}

/// The compensator a request names, and the feedback's gains it may give (track, tune); no
/// gains = designed per run.
inline constexpr std::array<ParamSpec, 1> kCompensator{{{"compensator", T::kString}}};
inline constexpr std::array<ParamSpec, 3> kGains{
    {{"kp", T::kNumber, 0.0, 1e6}, {"ki", T::kNumber, 0.0, 1e9}, {"kd", T::kNumber, 0.0, 1e3}}};
/// What every single-axis track takes beside its reference: preconditioning and learning.
inline constexpr std::array<ParamSpec, 7> kTrackRun{{{"force_gains", T::kBoolean},
                                                     {"precondition_s", T::kNumber, 0.0, 60.0},
                                                     {"learn_trials", T::kInteger, 0, 1000},
                                                     {"learn_gain", T::kNumber, 1e-3, 20.0},
                                                     {"learn_cutoff_hz", T::kNumber, 1e-3, 1e9},
                                                     {"learned", T::kString},
                                                     {"lead_in_max_s", T::kNumber, 0.0, 600.0}}};
/// A stage's decoupling of its axes' references.
inline constexpr std::array<ParamSpec, 2> kDecoupling{
    {{"decouple", T::kBoolean}, {"decoupling", T::kString}}};

}  // namespace request_fields

inline constexpr std::array<ParamSpec, 6> kIdentifyParams{
    {{"model", request_fields::T::kString},
     {"operators", request_fields::T::kInteger, 0, 500},
     {"dead_zones", request_fields::T::kInteger, -1, 100},
     {"u_min", request_fields::T::kNumber},
     {"u_max", request_fields::T::kNumber},
     {"extend", request_fields::T::kBoolean}}};

/// track with an uploaded reference (one axis).
inline constexpr auto kTrackUploadedParams = request_fields::join(
    std::array<ParamSpec, 2>{{{"reference_upload", request_fields::T::kString},
                              {"approach_s", request_fields::T::kNumber, 0.0, 60.0}}},
    request_fields::kCompensator, request_fields::kGains, request_fields::kTrackRun);

/// track on a stage with an uploaded reference per axis, {axis: upload name}.
inline constexpr auto kTrackStageUploadedParams = request_fields::join(
    std::array<ParamSpec, 2>{{{"reference_uploads", request_fields::T::kObject},
                              {"approach_s", request_fields::T::kNumber, 0.0, 60.0}}},
    request_fields::kCompensator,
    std::array<ParamSpec, 1>{{{"precondition_s", request_fields::T::kNumber, 0.0, 60.0}}},
    request_fields::kDecoupling);

/// track with a built-in reference (one axis, or a stage's with frequencies_hz and decoupling):
/// a stage's track reads the keys it shares with one axis's through this table.
inline constexpr auto kTrackBuiltinParams = request_fields::join(
    std::array<ParamSpec, 4>{
        {{"reference", request_fields::T::kString},
         {"frequency_hz", request_fields::T::kNumber, 1e-3},
         {"periods", request_fields::T::kNumber, 0.0, 1e7},
         {"duration_s", request_fields::T::kNumber, 0.0, request_fields::kWeekS}}},
    request_fields::kCompensator,
    std::array<ParamSpec, 3>{{{"range_fraction", request_fields::T::kNumber, 0.01, 1.0},
                              {"min_um", request_fields::T::kNumber, -1e9, 1e9},
                              {"max_um", request_fields::T::kNumber, -1e9, 1e9}}},
    request_fields::kGains, request_fields::kTrackRun,
    std::array<ParamSpec, 1>{{{"frequencies_hz", request_fields::T::kArray}}},
    request_fields::kDecoupling);

inline constexpr std::array<ParamSpec, 1> kExciteParams{
    {{"drive_upload", request_fields::T::kString}}};
/// excite on a stage: a complete drive upload per axis.
inline constexpr std::array<ParamSpec, 1> kExciteStageParams{
    {{"drive_uploads", request_fields::T::kObject}}};
inline constexpr std::array<ParamSpec, 2> kFrfParams{
    {{"amplitude", request_fields::T::kNumber, 1e-3, 0.1},
     {"periods", request_fields::T::kInteger, 2, 64}}};
inline constexpr auto kTuneParams =
    request_fields::join(request_fields::kCompensator, request_fields::kGains);

}  // namespace hystbench::daemon::details
