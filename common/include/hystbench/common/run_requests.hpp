#pragma once
// The parameters of each run command's request, one table each (key, type, range, meaning,
// default), shared by the two programs: the daemon's command table points at them, its run
// builders read the keys and their defaults through them, and docs/reference/protocol.md's
// tables are made from them (scripts/protocol-reference.sh); the CLI's options that set a key
// take its range and default from them. A key two requests share is defined once here. Ranges
// that depend on the bench (frequency_hz up to a twentieth of the loop rate, identify's
// u_min/u_max within the output limits) are checked by the run builders on top of these.
#include <array>

#include "hystbench/common/fit_families.hpp"
#include "hystbench/common/request_schema.hpp"

namespace hystbench::common {

namespace request_fields {

using T = ParamType;

inline constexpr double kWeekS = 7.0 * 24 * 3600;

/// The compensator a track names, and the feedback's gains it may give (track, tune); no
/// gains = designed per run.
inline constexpr std::array<ParamSpec, 1> kCompensator{
    {{.key = "compensator",
      .type = T::kString,
      .doc = "`none`, `inverse`, `inverse_multiplicative`, `inverse+pid` or `pid`",
      .fallback_doc = "`inverse` with a model, else `none`"}}};
inline constexpr std::array<ParamSpec, 3> kGains{
    {{.key = "kp",
      .type = T::kNumber,
      .lo = 0.0,
      .hi = 1e6,
      .doc = "feedback proportional gain [V/µm] instead of the designed loop",
      .fallback_doc = "`[pid]`'s gains where given, else the loop designed per run"},
     {.key = "ki",
      .type = T::kNumber,
      .lo = 0.0,
      .hi = 1e9,
      .doc = "feedback integral gain [V/(µm s)]",
      .fallback_doc = "as `kp`"},
     {.key = "kd",
      .type = T::kNumber,
      .lo = 0.0,
      .hi = 1e3,
      .doc = "feedback derivative gain [V s/µm]",
      .fallback_doc = "as `kp`"}}};
inline constexpr ParamSpec kPrecondition{
    .key = "precondition_s",
    .type = T::kNumber,
    .lo = 0.0,
    .hi = 60.0,
    .doc = "open-loop sweep u_max → u_min before the reference [s]",
    .fallback_doc = "`[identify] precondition_s`"};
inline constexpr ParamSpec kApproach{
    .key = "approach_s",
    .type = T::kNumber,
    .lo = 0.0,
    .hi = 60.0,
    .doc =
        "uploaded reference: unscored move to its first value [s] (longer where the slew "
        "limit needs it)",
    .fallback = "0.2"};
/// What every single-axis track takes beside its reference: preconditioning and learning.
inline constexpr std::array<ParamSpec, 7> kTrackRun{
    {{.key = "force_gains",
      .type = T::kBoolean,
      .doc = "run gains that break the loop's targets (refused with `unsafe_gains` otherwise)",
      .fallback_doc = "`[pid] force`"},
     kPrecondition,
     {.key = "learn_trials",
      .type = T::kInteger,
      .lo = 0,
      .hi = 1000,
      .doc = "learn over this many trials (a period, or a pass of an upload)",
      .fallback = "0"},
     {.key = "learn_gain",
      .type = T::kNumber,
      .lo = 1e-3,
      .hi = 20.0,
      .doc = "share of the error corrected per trial at the start (only with `learn_trials`)",
      .fallback = "0.5"},
     {.key = "learn_cutoff_hz",
      .type = T::kNumber,
      .lo = 1e-3,
      .hi = 1e9,
      .doc = "the learning's low-pass cut-off [Hz], at most 0.45 of the loop rate (only with "
             "`learn_trials`)",
      .fallback_doc = "from the loop rate, the frequency and the model"},
     {.key = "learned",
      .type = T::kString,
      .doc = "start from a drive learned before (its run id): one scored period, or the first "
             "trial with `learn_trials`"},
     {.key = "lead_in_max_s",
      .type = T::kNumber,
      .lo = 0.0,
      .hi = 600.0,
      .doc = "with `learned`: the longest lead-in [s] while the actuator's offset moves toward "
             "the one the drive was learned at (0: the shortest)",
      .fallback = "60"}}};
/// A stage's decoupling of its axes' references.
inline constexpr std::array<ParamSpec, 2> kDecoupling{
    {{.key = "decouple",
      .type = T::kBoolean,
      .doc = "a stage: take the coupling out of each axis's feedforward target",
      .fallback = "true"},
     {.key = "decoupling",
      .type = T::kString,
      .doc = "a stage: `static` (the coupling's gains) or `dynamic` (each coupling path's modes "
             "and lag too, fitted to the responses identify measured)",
      .fallback = "static"}}};

}  // namespace request_fields

inline constexpr std::array<ParamSpec, 6> kIdentifyParams{
    {{.key = "model",
      .type = request_fields::T::kString,
      .doc = "the model family (`auto`: chosen by held-out error)",
      .fallback_doc = "`[identify] model`",
      .values = fit_family_name_list},
     {.key = "operators",
      .type = request_fields::T::kInteger,
      .lo = 0,
      .hi = 500,
      .doc = "number of play operators; 0 = chosen by held-out error",
      .fallback_doc = "`[identify] operators`"},
     {.key = "dead_zones",
      .type = request_fields::T::kInteger,
      .lo = -1,
      .hi = 100,
      .doc = "dead-zone operators per side; -1 = chosen by held-out error",
      .fallback_doc = "`[identify] dead_zones`"},
     {.key = "u_min",
      .type = request_fields::T::kNumber,
      .doc = "the excitation's lowest drive [V], within the output limits",
      .fallback_doc = "`[identify]`'s span of the limits"},
     {.key = "u_max",
      .type = request_fields::T::kNumber,
      .doc = "the excitation's highest drive [V], within the output limits",
      .fallback_doc = "`[identify]`'s span of the limits"},
     {.key = "extend",
      .type = request_fields::T::kBoolean,
      .doc = "diagnose the record and extend the model where that tracks better",
      .fallback_doc = "`[identify] extend`"}}};

/// track with an uploaded reference (one axis).
inline constexpr auto kTrackUploadedParams = request_fields::join(
    std::array<ParamSpec, 2>{
        {{.key = "reference_upload",
          .type = request_fields::T::kString,
          .doc = "an upload of kind `reference` (`upload.begin`), in place of the built-in "
                 "reference"},
         request_fields::kApproach}},
    request_fields::kCompensator, request_fields::kGains, request_fields::kTrackRun);

/// track on a stage with an uploaded reference per axis, {axis: upload name}.
inline constexpr auto kTrackStageUploadedParams = request_fields::join(
    std::array<ParamSpec, 2>{
        {{.key = "reference_uploads",
          .type = request_fields::T::kObject,
          .doc = "a stage: `{axis: upload}`, an uploaded reference for every axis, in place of "
                 "the built-in one"},
         request_fields::kApproach}},
    request_fields::kCompensator, std::array<ParamSpec, 1>{{request_fields::kPrecondition}},
    request_fields::kDecoupling);

/// track with a built-in reference (one axis, or a stage's with frequencies_hz and decoupling):
/// a stage's track reads the keys it shares with one axis's through this table.
inline constexpr auto kTrackBuiltinParams = request_fields::join(
    std::array<ParamSpec, 4>{
        {{.key = "reference",
          .type = request_fields::T::kString,
          .doc = "`sine`, `triangle`, `sawtooth`, `step` (a square wave: the result adds `step`, "
                 "each step's settling time to 1 % and overshoot), `decaying_sine`, "
                 "`multi_frequency`, `chirp`; on a stage `raster`, `lissajous` or `spiral`",
          .fallback = "triangle",
          .fallback_doc = "`raster` on a stage"},
         {.key = "frequency_hz",
          .type = request_fields::T::kNumber,
          .lo = 1e-3,
          .doc = "the reference's frequency [Hz], at most a twentieth of the loop rate",
          .fallback = "1"},
         {.key = "periods",
          .type = request_fields::T::kNumber,
          .lo = 0.0,
          .hi = 1e7,
          .doc = "number of periods",
          .fallback = "5"},
         {.key = "duration_s",
          .type = request_fields::T::kNumber,
          .lo = 0.0,
          .hi = request_fields::kWeekS,
          .doc = "duration [s], instead of `periods`",
          .fallback_doc = "`periods` / `frequency_hz`; on a stage 10 (`raster`, `spiral`) or 2 "
                          "(`lissajous`)"}}},
    request_fields::kCompensator,
    std::array<ParamSpec, 3>{{{.key = "range_fraction",
                               .type = request_fields::T::kNumber,
                               .lo = 0.01,
                               .hi = 1.0,
                               .doc = "part of the actuator's range the reference spans, centred",
                               .fallback = "0.8",
                               .fallback_doc = "0.2 for `step`"},
                              {.key = "min_um",
                               .type = request_fields::T::kNumber,
                               .lo = -1e9,
                               .hi = 1e9,
                               .doc = "the reference's minimum [µm], instead of `range_fraction`"},
                              {.key = "max_um",
                               .type = request_fields::T::kNumber,
                               .lo = -1e9,
                               .hi = 1e9,
                               .doc = "the reference's maximum [µm]"}}},
    request_fields::kGains, request_fields::kTrackRun,
    std::array<ParamSpec, 1>{
        {{.key = "frequencies_hz",
          .type = request_fields::T::kArray,
          .doc = "a stage's built-in reference: `raster` [fast, slow], `lissajous` one per axis, "
                 "`spiral` [turns per second]; each at most a twentieth of the loop rate",
          .fallback_doc = "[10, 0.1] (`raster`), 10, 11, ... (`lissajous`), [10] (`spiral`)"}}},
    request_fields::kDecoupling);

inline constexpr std::array<ParamSpec, 1> kExciteParams{{{.key = "drive_upload",
                                                          .type = request_fields::T::kString,
                                                          .doc = "an upload of kind `drive`"}}};
/// excite on a stage: a complete drive upload per axis.
inline constexpr std::array<ParamSpec, 1> kExciteStageParams{
    {{.key = "drive_uploads",
      .type = request_fields::T::kObject,
      .doc = "on a stage: `{axis: upload}`, a `drive` upload for every axis"}}};
inline constexpr std::array<ParamSpec, 2> kFrfParams{
    {{.key = "amplitude",
      .type = request_fields::T::kNumber,
      .lo = 1e-3,
      .hi = 0.1,
      .doc = "the small multisines' peak, a share of the drive span (the larger one 4x)",
      .fallback = "0.02"},
     {.key = "periods",
      .type = request_fields::T::kInteger,
      .lo = 2,
      .hi = 64,
      .doc = "periods averaged per condition",
      .fallback = "4"}}};
/// tune: the loop a track would get; the compensators with feedback only.
inline constexpr auto kTuneParams = request_fields::join(
    std::array<ParamSpec, 1>{{{.key = "compensator",
                               .type = request_fields::T::kString,
                               .doc = "`inverse+pid` or `pid`",
                               .fallback_doc = "`inverse+pid` with a model, else `pid`"}}},
    request_fields::kGains);

}  // namespace hystbench::common
