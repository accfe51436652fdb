#include "hystbench/daemon/runs/track_drive.hpp"

#include <algorithm>

#include "hystbench/daemon/loop/sample_record.hpp"

namespace hystbench::daemon {

namespace {
constexpr double kNoTwin = std::numeric_limits<double>::quiet_NaN();
}  // namespace

double TrackProgram::feedforward_target(double t_s, double tare_um) const noexcept {
  const sim::SignalGenerator& r = feedforward_reference ? *feedforward_reference : *reference;
  if (!preview) return std::clamp(r.value(t_s), y_ref_min, y_ref_max) - tare_um;
  const double tl = t_s + preview->lead_s(), h = preview->step_s();
  return preview->target(r.value(tl - h), r.value(tl), r.value(tl + h)) - tare_um;
}

double TrackProgram::clipped_reference(double t_s) const noexcept {
  return std::clamp(reference->value(t_s), y_ref_min, y_ref_max);
}

void TrackDrive::configure(const DriveSetup& setup) {
  const TrackProgram& p = program;
  state_ = TrackState{};
  state_.dt = setup.dt_s;
  state_.first_tick = setup.first_tick;
  if (p.compensator) state_.compensator.emplace(*p.compensator);
  if (p.learned_twin) state_.learned_twin.emplace(*p.learned_twin);
  // The targets ahead, for an inverse that uses them. Not yet with a dynamics preview, whose
  // target is already computed from the reference ahead: fed both, the rate inverse tracked
  // worse.
  state_.targets.allocate(p.compensator && !p.preview ? p.compensator->preview_samples() : 0);
  state_.twin_targets.allocate(p.learned_twin && !p.preview ? p.learned_twin->preview_samples()
                                                            : 0);
  // The feedback's integral holds while the drive sits at a bound of the output range.
  if (state_.compensator) state_.compensator->set_drive_range(setup.u_min, setup.u_max);
  if (state_.learned_twin) state_.learned_twin->set_drive_range(setup.u_min, setup.u_max);
}

bool TrackDrive::awaits(std::uint64_t k) const noexcept {
  return learning && k >= learning->first_scored_tick() && learning->owed(k);
}

double TrackDrive::twin_feedforward(double t) noexcept {
  const double none = std::numeric_limits<double>::quiet_NaN();  // its feedback holds
  const TrackProgram& p = program;
  auto target_at = [&p](double tt) noexcept {
    return p.feedforward_target(tt, p.learned_twin_offset_um);
  };
  TrackState& s = state_;
  if (s.twin_targets.capacity() > 1) {
    return s.learned_twin->step(none, none, s.twin_targets.advance(t, s.dt, target_at)).u_ff;
  }
  return s.learned_twin->step(none, none, target_at(t)).u_ff;
}

DriveCommand TrackDrive::update(const DriveInput& in) noexcept {
  const TrackProgram& p = program;
  TrackState& s = state_;
  const std::uint64_t k = in.k;
  DriveCommand d;
  s.trial_tick = s.lead_in = false;
  const double t = static_cast<double>(k - s.first_tick) * s.dt;
  d.y_ref = p.reference->value(t);
  if (d.y_ref < p.y_ref_min || d.y_ref > p.y_ref_max) {
    d.y_ref = std::min(std::max(d.y_ref, p.y_ref_min), p.y_ref_max);
    d.flags |= kSampleReferenceLimited;
  }
  // The feedforward's target at time tt: the reference, or with a preview the static target
  // that inverts the model's delay and dynamics (the reference ahead by the delay). Less the
  // tare: the output offset the model did not predict on the sweep, and from the first scored
  // tick of a periodic reference the mean error of its start-up period. A drive learned before:
  // the offset taken off when it was learned, and from trial 0 on also the offset its lead-in
  // measured.
  const double tare_um =
      learning ? learning->target_offset(k, s.tare.um()) : s.tare.um_at(k, p.tare);
  auto target_at = [&p, tare_um](double tt) noexcept { return p.feedforward_target(tt, tare_um); };
  // The feedback's reference; NaN before the feedback may act: the PID holds.
  const double fb_ref = in.feedback_on ? d.y_ref : std::numeric_limits<double>::quiet_NaN();
  // The compensator compares the reading with the reference of the tick before. A reading that
  // answered late (ReadingLateness) is moved by the reference's motion since the tick it
  // answered, so that the feedback sees the stage's error and not the exchange's lateness.
  double y = in.y;
  if (in.y_late_ticks > 0 && std::isfinite(y)) {
    y += p.clipped_reference(std::max(0.0, t - s.dt)) -
         p.clipped_reference(std::max(0.0, t - s.dt * static_cast<double>(1 + in.y_late_ticks)));
  }
  if (k == p.harmonics_from && k > 0 && s.compensator) s.compensator->restart_harmonics();
  compensation::CompensatorOutput out;
  if (s.targets.capacity() > 1) {
    out = s.compensator->step(fb_ref, y, s.targets.advance(t, s.dt, target_at));
  } else {
    out = s.compensator->step(fb_ref, y, target_at(t));
  }
  const double twin = s.learned_twin ? twin_feedforward(t) : kNoTwin;
  d.u_ff = out.u_ff;
  d.u_fb = out.u_fb;
  s.u_compensator = out.u_ff;
  if (out.feedback_saturated) d.flags |= kSampleFeedbackSaturated;
  d.u = out.u;
  if (learning && k >= learning->first_scored_tick()) {
    // A learning run: from trial 1 on the learned feedforward, with the feedback on it.
    s.phase = learning->begin_tick(k);
    s.trial_tick = true;
    d.trial_ends = s.phase + 1 == learning->period;
    if (double u_ff = out.u_ff; learning->learned(s.phase, u_ff, twin)) {
      d.u_ff = u_ff;
      d.u = u_ff + out.u_fb;
    }
  } else if (double u_ff = out.u_ff; learning && learning->lead_in(k, u_ff, twin)) {
    d.u_ff = u_ff;  // a drive learned before plays the start-up period too
    d.u = u_ff + out.u_fb;
    s.lead_in = true;
  }
  return d;
}

void TrackDrive::limited(int direction) noexcept {
  if (state_.compensator) state_.compensator->notify_saturation(direction);
}

void TrackDrive::predicted(std::uint64_t k, double y_model) noexcept {
  state_.tare.y_model_history[k % TareMeasure::kHistory] = y_model;
  state_.tare.predicted = true;
}

void TrackDrive::measured(std::uint64_t k, const drivers::Measurement& m) noexcept {
  // A fresh reading on the sweep less the model's prediction for the output it answers (the
  // reading answers the output of response_ticks ago, less the exchange latency the model's
  // delay holds).
  const TareWindow& w = program.tare;
  TareMeasure& tare = state_.tare;
  const std::uint64_t lag =
      m.response_ticks > w.model_exchange_ticks ? m.response_ticks - w.model_exchange_ticks : 0;
  if (tare.predicted && k >= w.from && k < state_.first_tick && lag < TareMeasure::kHistory &&
      lag <= k) {
    tare.sum += m.position_um - tare.y_model_history[(k - lag) % TareMeasure::kHistory];
    ++tare.samples;
  }
}

DriveScore TrackDrive::scored(std::uint64_t k, double y_ref, double y_measured,
                              double u_ff) noexcept {
  const TareWindow& w = program.tare;
  TrackState& st = state_;
  DriveScore s;
  if (k >= w.startup_from && k < w.startup_to && std::isfinite(y_ref) &&
      std::isfinite(y_measured)) {
    st.tare.startup_sum += y_measured - y_ref;
    ++st.tare.startup_samples;
  }
  if (st.lead_in) {
    learning->lead_in_error(k, y_ref - y_measured, st.tare.um());
    s.scored_from = learning->first_scored_tick();  // a lead-in that ends early moves it up
  }
  if (st.trial_tick) {
    s.last_trial = learning->end_tick(st.phase, u_ff, st.u_compensator, y_ref - y_measured);
  }
  return s;
}

TrackDrive* track_drive(RunProgram& p) noexcept { return dynamic_cast<TrackDrive*>(p.drive.get()); }

const TrackDrive* track_drive(const RunProgram& p) noexcept {
  return dynamic_cast<const TrackDrive*>(p.drive.get());
}

TrackDrive& make_track_drive(RunProgram& p) {
  auto drive = std::make_unique<TrackDrive>();
  TrackDrive& out = *drive;
  p.drive = std::move(drive);
  return out;
}

}  // namespace hystbench::daemon
