// jointcomp montecarlo and jointcomp fleet: thin commands that check their options (CLI11: --help, usage and
// exit 2 on bad ones) and hand the work to Python, `/usr/bin/python3 -m jointcomp.distributed <command>`
// (capi/python/jointcomp/distributed/), which spreads it over a Dask cluster. The child is started from an
// argument vector (no shell), with PYTHONPATH and JOINTCOMP_LIBRARY naming this installation's (or build
// tree's) package and library, and dies with its parent.
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include "cli/commands.hpp"
#include "cli/file_locations.hpp"
#include "cli/options.hpp"
#include "cli/output_paths.hpp"

extern char** environ;

namespace jointcomp::cli {
namespace {

constexpr const char* kPython = "/usr/bin/python3";  // Debian's, with python3-distributed and numpy
// The most draws of one Monte Carlo run (jointcomp.distributed.MAX_SAMPLES): the draws are reduced on the
// workers, so memory does not grow with them; the per-draw CSV then holds about 1.5 GB.
constexpr long long kMaxSamples = 10000000;
constexpr long long kMaxBatch = 1000000;
constexpr long long kMaxWorkers = 1024;
constexpr double kMaxTimeout = 1e7;  // s, about 4 months

bool exists(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0;
}

// The Python package's folder and the C library the child is to use: installed, <prefix>/lib/python3/
// dist-packages and <prefix>/<libdir>/libjointcomp.so.1 beside <prefix>/bin/jointcomp; otherwise the
// source tree's capi/python and the build tree's library.
struct PythonSide {
  std::string package_root;
  std::string library;
};

PythonSide pythonSide() {
  const FileLocations& files = fileLocations();
  if (files.installed) {
    // files.data is <prefix>/share/jointcomp, resolved.
    const std::string prefix = files.data + "/../..";
    return {prefix + "/" + JOINTCOMP_PYTHON_INSTALL_DIR, prefix + "/" + JOINTCOMP_LIBRARY_INSTALL_PATH};
  }
  return {JOINTCOMP_PYTHON_SOURCE_DIR, JOINTCOMP_LIBRARY_BUILD_PATH};
}

// The child's environment: ours with PYTHONPATH (the package first) and JOINTCOMP_LIBRARY set.
std::vector<std::string> childEnvironment(const PythonSide& side) {
  std::vector<std::string> environment;
  std::string python_path = side.package_root;
  for (char** e = environ; *e; ++e) {
    const std::string entry(*e);
    if (entry.rfind("PYTHONPATH=", 0) == 0) {
      if (entry.size() > 11) python_path += ":" + entry.substr(11);
    } else if (entry.rfind("JOINTCOMP_LIBRARY=", 0) != 0) {
      environment.push_back(entry);
    }
  }
  environment.push_back("PYTHONPATH=" + python_path);
  environment.push_back("JOINTCOMP_LIBRARY=" + side.library);
  return environment;
}

// Runs python3 -m jointcomp.distributed with `arguments`; its exit status, or 1 when it could not run.
int runPython(const std::vector<std::string>& arguments) {
  const PythonSide side = pythonSide();
  if (!exists(side.package_root + "/jointcomp/distributed/__main__.py")) {
    std::fprintf(stderr, "jointcomp: the Python package is not at %s (jointcomp/distributed/__main__.py)\n",
                 side.package_root.c_str());
    return 1;
  }
  if (!exists(side.library)) {
    std::fprintf(stderr, "jointcomp: the library %s is not there (build the jointcomp_capi target)\n",
                 side.library.c_str());
    return 1;
  }
  std::vector<std::string> argv_text = {kPython, "-m", "jointcomp.distributed"};
  argv_text.insert(argv_text.end(), arguments.begin(), arguments.end());
  const std::vector<std::string> environment = childEnvironment(side);
  std::vector<char*> argv, envp;
  for (const std::string& a : argv_text) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  for (const std::string& e : environment) envp.push_back(const_cast<char*>(e.c_str()));
  envp.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t parent = getpid();
  const pid_t child = fork();
  if (child < 0) {
    std::fprintf(stderr, "jointcomp: cannot start %s: %s\n", kPython, std::strerror(errno));
    return 1;
  }
  if (child == 0) {
    // Dies with the parent; if the parent is already gone, do not start.
    if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent) _exit(127);
    execve(kPython, argv.data(), envp.data());
    _exit(127);
  }
  // Ctrl-C reaches the whole foreground group: the child stops its run itself (cluster closed, temporary
  // folders removed, checkpoint kept, exit 130), so this process waits for it instead of dying and taking the
  // child down with it (PR_SET_PDEATHSIG) before it could clean up. The child started with the default action.
  struct sigaction ignore {
  }, old_interrupt{}, old_quit{};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  sigaction(SIGINT, &ignore, &old_interrupt);
  sigaction(SIGQUIT, &ignore, &old_quit);
  int status = 0;
  pid_t waited = 0;
  while ((waited = waitpid(child, &status, 0)) < 0 && errno == EINTR) {}
  const int wait_error = errno;
  sigaction(SIGINT, &old_interrupt, nullptr);
  sigaction(SIGQUIT, &old_quit, nullptr);
  if (waited < 0) {
    std::fprintf(stderr, "jointcomp: lost the Python process: %s\n", std::strerror(wait_error));
    return 1;
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127) {
    std::fprintf(stderr,
                 "jointcomp: %s could not be run (needs Debian's python3, python3-numpy and "
                 "python3-distributed: packaging/install-deps.sh)\n",
                 kPython);
    return 1;
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  std::fprintf(stderr, "jointcomp: the Python process was killed by signal %d\n", WTERMSIG(status));
  return 1;
}

// Parses with CLI11 as every command does (cli/options.hpp): --help exits 0, a bad command line 2.
void parse(CLI::App& app, int argc, char** argv) {
  app.set_help_flag("-h,--help", "this help");
  parseCommandLine(app, argc, argv);
}

// Why `text` is no Dask scheduler address (PROTOCOL://HOST:PORT or HOST:PORT), or "" when it is one: a
// garbage address made Dask try for 120 s and end in a traceback.
std::string schedulerAddressProblem(const std::string& text) {
  std::string rest = text;
  const std::size_t scheme = text.find("://");
  if (scheme != std::string::npos) {
    const std::string protocol = text.substr(0, scheme);
    if (protocol != "tcp" && protocol != "tls" && protocol != "ucx" && protocol != "ws" && protocol != "wss")
      return excerpt(text) + " is not a scheduler address: the protocol must be tcp, tls, ucx, ws or wss";
    rest = text.substr(scheme + 3);
  }
  const std::size_t colon = rest.rfind(':');
  const std::string host = colon == std::string::npos ? "" : rest.substr(0, colon);
  const std::string port = colon == std::string::npos ? "" : rest.substr(colon + 1);
  const bool plain_host = !host.empty() && host.find_first_of(" /\t\n") == std::string::npos;
  if (!plain_host || !integerProblem(port, 1, 65535).empty())
    return excerpt(text) + " is not a scheduler address (PROTOCOL://HOST:PORT, e.g. tcp://10.0.0.5:8786)";
  return "";
}

struct ClusterOptions {
  std::string scheduler;
  std::string dashboard;
  int workers = 0;
  double timeout = 3600.0;

  void add(CLI::App& app) {
    app.add_option("--scheduler", scheduler,
                   "address of a running Dask scheduler, e.g. tcp://host:8786 "
                   "(default: a local cluster of worker processes)")
        ->check(std::function<std::string(const std::string&)>(schedulerAddressProblem));
    app.add_option("--workers", workers,
                   "local worker processes, 1 to " + std::to_string(kMaxWorkers) + " (default: the machine's cores)")
        ->check(integerCheck(1, kMaxWorkers));
    app.add_option("--timeout", timeout, "seconds for all tasks, then an error (at most 1e7)")
        ->check(numberCheck({0.0, kMaxTimeout, true}));
    app.add_option("--dashboard", dashboard,
                   "serve the local cluster's Dask dashboard at this address, e.g. 127.0.0.1:8787 (default: none)");
  }
  void append(std::vector<std::string>& arguments) const {
    if (!scheduler.empty()) arguments.insert(arguments.end(), {"--scheduler", scheduler});
    if (workers > 0) arguments.insert(arguments.end(), {"--workers", std::to_string(workers)});
    if (!dashboard.empty()) arguments.insert(arguments.end(), {"--dashboard", dashboard});
    char text[64];
    std::snprintf(text, sizeof text, "%.17g", timeout);
    arguments.insert(arguments.end(), {"--timeout", text});
  }
};

}  // namespace

int runMonteCarlo(int argc, char** argv) {
  CLI::App app(
      "the paper's spiral under parameter uncertainty: N parameter sets drawn from a report's standard "
      "errors, a distribution file or the main job's perturbation; the compensation uses the nominal "
      "parameters, the simulated robot each drawn set. Prints the percentiles of Ra, Rz, RMS and max "
      "error and the 95 % bounds; writes montecarlo.json, montecarlo.csv and montecarlo_band.png",
      "jointcomp montecarlo");
  std::string urdf = robotFile("rx170"), params = parameterFile("rx170"), report, distribution, out = "out/montecarlo";
  int samples = 100;
  long long seed = 2019;
  bool plant = false, resume = false;
  long long batch = 0;
  app.add_option("--urdf", urdf, optionHelp("urdf"))->check(CLI::ExistingFile);
  app.add_option("--params", params, "the nominal (identified) parameter file")->check(CLI::ExistingFile);
  auto* report_option = app.add_option("--report", report,
                                       "report.json of identify, calibrate or discover: its standard errors are the "
                                       "law")
                            ->check(CLI::ExistingFile);
  app.add_option("--distribution", distribution, "JSON file: a list of {parameter, law, scale, relative}")
      ->check(CLI::ExistingFile)
      ->excludes(report_option);
  app.add_option("--samples", samples, "number of draws, 1 to " + std::to_string(kMaxSamples))
      ->check(integerCheck(1, kMaxSamples));
  app.add_option("--seed", seed, "random seed, 0 to 2^62 (draw k uses its own generator of seed and k)")
      ->check(integerCheck(0, kMaxSeed));
  app.add_flag("--plant", plant, "simulate the flexible-joint plant (needs drives) instead of the quasi-static robot");
  app.add_option("--out", out, "output folder");
  app.add_flag("--resume", resume,
               "continue the run stopped (Ctrl-C, a lost scheduler, a kill) whose checkpoint is in --out: the same "
               "results as a run never stopped");
  app.add_option("--batch", batch,
                 "draws per task, 1 to " + std::to_string(kMaxBatch) + " (default: about 2 s of work)")
      ->check(integerCheck(1, kMaxBatch));
  ClusterOptions cluster;
  cluster.add(app);
  parse(app, argc, argv);
  prepareOutputFolder(out);  // before any work, as every command does
  std::vector<std::string> arguments = {
      "montecarlo",         "--urdf", urdf, "--params", params, "--samples", std::to_string(samples), "--seed",
      std::to_string(seed), "--out",  out};
  if (!report.empty()) arguments.insert(arguments.end(), {"--report", report});
  if (!distribution.empty()) arguments.insert(arguments.end(), {"--distribution", distribution});
  if (plant) arguments.push_back("--plant");
  if (resume) arguments.push_back("--resume");
  if (batch > 0) arguments.insert(arguments.end(), {"--batch", std::to_string(batch)});
  cluster.append(arguments);
  return runPython(arguments);
}

int runFleet(int argc, char** argv) {
  CLI::App app(
      "calibrates (or runs discovery on) many robots, one campaign file each: a report folder per robot "
      "and a fleet summary (fleet_summary.csv/.json/.txt, fleet.png) with outliers flagged (after-RMS "
      "above median + 3 x 1.4826 x MAD)",
      "jointcomp fleet");
  std::string urdf = robotFile("rx170"), params = parameterFile("rx170"), method = "calibrate", out = "out/fleet";
  std::vector<std::string> campaigns;
  app.add_option("--urdf", urdf, optionHelp("urdf"))->check(CLI::ExistingFile);
  app.add_option("--params", params, "the nominal parameter file")->check(CLI::ExistingFile);
  app.add_option("--campaign", campaigns, "campaign files, one robot each (several after one --campaign, or repeated)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--method", method, "calibrate or discover")->check(CLI::IsMember({"calibrate", "discover"}));
  app.add_option("--out", out, "output folder");
  std::vector<std::string> holdouts;
  app.add_option(
         "--holdout", holdouts,
         "CAMPAIGN=HELD_OUT.csv: a held-out campaign of that campaign's robot (frame re-fitted; repeat for more)")
      ->check([](const std::string& item) {
        const std::size_t at = item.find('=');
        if (at == std::string::npos || at == 0 || at + 1 == item.size())
          return std::string("expected CAMPAIGN=HELD_OUT.csv");
        return CLI::ExistingFile(item.substr(at + 1)).empty() ? std::string() : "no file " + item.substr(at + 1);
      });
  ClusterOptions cluster;
  cluster.add(app);
  parse(app, argc, argv);
  prepareOutputFolder(out);  // before any work, as every command does
  std::vector<std::string> arguments = {"fleet", "--urdf", urdf, "--params", params, "--method", method, "--out", out};
  for (const std::string& campaign : campaigns) arguments.insert(arguments.end(), {"--campaign", campaign});
  for (const std::string& holdout : holdouts) arguments.insert(arguments.end(), {"--holdout", holdout});
  cluster.append(arguments);
  return runPython(arguments);
}

}  // namespace jointcomp::cli
