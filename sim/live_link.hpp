// The controller side of a live loop on the virtual machine (seed 004 Fig. 6.2: the PC reads
// the temperatures and the cycle's log, writes offsets and the measurement interval into the
// CNC). The virtual machine calls the link as a controller would expose its data, in its own
// clock, single-threaded, so a closed-loop campaign is as deterministic as an open one:
// - every line it writes to a log, right after writing it; every inputs sample, right after
//   taking it (the link sees the data exactly when a live loop on a real machine could);
// - before each block's motion (rapid, feed, probe, dwell) it asks for the axis offsets in
//   effect now at the nominal tip position and B (a trunnion's offsets turn with B), and adds them to the commanded X Y Z as external
//   offsets do (LinuxCNC eoffsets, a Fanuc work-offset shift): the reported probe positions
//   stay in the program's frame, the real tip moves by the offset;
// - a program that reads an externally written value (Fanuc common variable #500..#999 as a
//   FOCAS writer sets it, LinuxCNC M66 analog input) gets the link's answer at that instant.
#pragma once
#include <Eigen/Dense>
#include <optional>
#include <string>

namespace probeloop::sim {

class LiveLink {
 public:
  virtual ~LiveLink() = default;
  virtual void logLine(double t_s, const std::string& log_name, const std::string& line) = 0;
  // header: the inputs CSV's lines before the first row (given with every call; the same).
  virtual void inputSample(double t_s, const std::string& header, const std::string& row) = 0;
  virtual Eigen::Vector3d offsetsUm(double t_s, const Eigen::Vector3d& tip_mm, double b_deg) = 0;
  virtual std::optional<double> externalVariable(double t_s, int n) = 0;
  virtual double analogInput(double t_s, int n) = 0;
};

}  // namespace probeloop::sim
