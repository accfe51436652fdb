#include "hystbench/cli/report/loop_plots.hpp"

#include <cmath>
#include <fstream>
#include <stdexcept>
#include <string>

#include "report/details/gnuplot.hpp"

namespace hystbench::cli {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::ofstream open_for_writing(const fs::path& p) {
  std::ofstream f(p, std::ios::trunc);
  if (!f) throw std::runtime_error(p.string() + ": cannot write");
  f.precision(9);
  return f;
}

// gnuplot's name for a label: underscores would start subscripts.
std::string plain(std::string s) {
  for (char& c : s) {
    if (c == '_' || c == '\'') c = ' ';
  }
  return s;
}

// "plot DATA index 0 u X:Y w l title 'a', '' index 1 ..." over the blocks.
std::string curves(const std::string& data, const json& labels, const std::string& columns,
                   const std::string& style) {
  std::string s;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (i > 0) s += ", ";
    s += data;
    s += " index " + std::to_string(i);
    s += " using " + columns;
    s += " with " + style;
    s += " lc " + std::to_string(i + 1);
    s += " title '" + plain(labels[i].get<std::string>()) + "'";
  }
  return s;
}

}  // namespace

std::vector<fs::path> plot_responses(const json& measured, const fs::path& dir) {
  const json& responses = measured.at("responses");
  if (!responses.is_array() || responses.empty()) {
    throw std::runtime_error("response.png: no measured response");
  }
  fs::create_directories(dir);
  const fs::path dat = dir / "response.dat";
  std::ofstream d = open_for_writing(dat);
  json labels = json::array();
  for (const json& r : responses) {
    d << "# " << r.value("label", "") << ": f_hz magnitude phase_deg coherence\n";
    const auto& f = r.at("frequency_hz");
    for (std::size_t i = 0; i < f.size(); ++i) {
      const double re = r.at("real")[i].get<double>(), im = r.at("imag")[i].get<double>();
      d << f[i].get<double>() << ' ' << std::hypot(re, im) << ' '
        << std::atan2(im, re) * 180.0 / M_PI << ' ' << r.at("coherence")[i].get<double>() << '\n';
    }
    d << "\n\n";
    labels.push_back(r.value("label", ""));
  }
  d.close();
  const fs::path png = dir / "response.png", script = dir / "response.gp";
  const std::string data = details::gnuplot_quoted(dat);
  std::ofstream gp = open_for_writing(script);
  gp << "set terminal pngcairo size 1000,900\nset output " << details::gnuplot_quoted(png)
     << "\nset multiplot layout 3,1 title 'measured frequency response (" +
            plain(measured.value("run_id", "")) + ")'\n"
     << "set logscale x\nset grid\nset key top left font ',9'\nset lmargin 12\n"
     << "set ylabel 'magnitude [um/V]'\nset logscale y\nplot "
     << curves(data, labels, "1:2", "lines") << "\nunset logscale y\n"
     << "set ylabel 'phase [deg]'\nplot " << curves(data, labels, "1:3", "lines") << "\n"
     << "set ylabel 'coherence'\nset xlabel 'f [Hz]'\nset yrange [0:1.05]\nplot "
     << curves(data, labels, "1:4", "lines") << "\nunset multiplot\n";
  gp.close();
  details::run_gnuplot(script, dir / "gnuplot.log");
  return {png};
}

std::vector<fs::path> plot_loop(const json& design, const fs::path& dir) {
  const json& curves_json = design.at("curves");
  if (!curves_json.is_array() || curves_json.empty()) throw std::runtime_error("no loop curve");
  fs::create_directories(dir);
  const fs::path dat = dir / "loop.dat";
  std::ofstream d = open_for_writing(dat);
  json labels = json::array();
  for (const json& c : curves_json) {
    d << "# " << c.value("response", "")
      << ": f_hz |L| arg_L_deg re_L im_L |S| |T| (the Nyquist frequency last)\n";
    const auto& f = c.at("frequency_hz");
    for (std::size_t i = 0; i < f.size(); ++i) {
      const double mag = c.at("loop_magnitude")[i].get<double>();
      const double ph = c.at("loop_phase_deg")[i].get<double>();
      d << f[i].get<double>() << ' ' << mag << ' ' << ph << ' ' << mag * std::cos(ph * M_PI / 180.0)
        << ' ' << mag * std::sin(ph * M_PI / 180.0) << ' ' << c.at("sensitivity")[i].get<double>()
        << ' ' << c.at("complementary")[i].get<double>() << '\n';
    }
    d << "\n\n";
    labels.push_back(c.value("response", ""));
  }
  d.close();
  const json targets = design.value("targets", json::object());
  const double s_max = std::pow(10.0, targets.value("peak_sensitivity_db", 6.0) / 20.0);
  const double xo = design.value("crossover_hz", 0.0);
  const std::string title = plain(design.value("structure", design.value("gains", std::string())));
  const std::string data = details::gnuplot_quoted(dat);
  std::vector<fs::path> pngs = {dir / "loop-bode.png", dir / "nyquist.png",
                                dir / "sensitivity.png"};
  const fs::path script = dir / "loop.gp";
  std::ofstream gp = open_for_writing(script);
  gp << "set terminal pngcairo size 1000,800\nset grid\nset key bottom left font ',9'\n"
     << "set lmargin 12\nset output " << details::gnuplot_quoted(pngs[0])
     << "\nset multiplot layout 2,1 title 'loop L = C z^{-1} P: " << title << "'\n"
     << "set logscale xy\nset ylabel '|L|'\n";
  if (xo > 0.0)
    gp << "set arrow 1 from " << xo << ", graph 0 to " << xo << ", graph 1 nohead dt 2\n";
  gp << "plot " << curves(data, labels, "1:2", "lines") << ", 1 with lines dt 3 lc 0 notitle\n"
     << "unset logscale y\nset ylabel 'arg L [deg]'\nset xlabel 'f [Hz]'\n"
     << "plot " << curves(data, labels, "1:3", "lines")
     << ", -180 with lines dt 3 lc 0 title '-180 deg', -180 + "
     << targets.value("phase_margin_deg", 45.0)
     << " with lines dt 2 lc 0 title 'phase margin target'\nunset multiplot\nunset arrow 1\n";
  gp << "set terminal pngcairo size 800,800\nset output " << details::gnuplot_quoted(pngs[1])
     << "\nunset logscale xy\nset size square\nset parametric\nset trange [0:2*pi]\n"
     << "set xrange [-3:1.5]\nset yrange [-2.25:2.25]\nset xlabel 'Re L'\nset ylabel 'Im L'\n"
     << "set object 1 circle at -1,0 size 0.04 fc rgb 'black' fillstyle solid\n"
     << "set title 'Nyquist: L stays outside the circle |1 + L| = " << 1.0 / s_max
     << " (peak |S| target)'\nplot " << curves(data, labels, "4:5", "lines") << ", -1 + "
     << 1.0 / s_max << "*cos(t), " << 1.0 / s_max
     << "*sin(t) with lines dt 2 lc 0 title '|S| target', cos(t), sin(t) with lines dt 3 lc 0 "
        "title 'unit circle'\n"
     << "unset parametric\nset size nosquare\nset autoscale xy\nunset object 1\n";
  gp << "set terminal pngcairo size 1000,600\nset output " << details::gnuplot_quoted(pngs[2])
     << "\nset logscale x\nset xlabel 'f [Hz]'\nset ylabel '[dB]'\n"
     << "set title 'sensitivity |S| (solid: error out / error in) and |T| (dashed: closed loop)'\n"
     << "set key bottom right\nplot " << curves(data, labels, "1:(20*log10($6))", "lines") << ", "
     << curves(data, labels, "1:(20*log10($7))", "lines dt 4") << ", " << 20.0 * std::log10(s_max)
     << " with lines dt 2 lc 0 title '|S| target', -3 with "
        "lines dt 3 lc 0 title '-3 dB'\n";
  gp.close();
  details::run_gnuplot(script, dir / "gnuplot.log");
  return pngs;
}

}  // namespace hystbench::cli
