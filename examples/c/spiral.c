/* The paper's spiral (Olabi et al., IEEE ICIT 2012, Table II) through the jointcomp C API: the three runs
 * (no correction, stiffness correction, stiffness and kinematic correction) of a simulated RX170, with
 * their Ra and Rz.
 *
 * usage: spiral [robot.urdf parameters.json]
 * Build: see CMakeLists.txt here (find_package), or
 *   cc spiral.c $(pkg-config --cflags --libs jointcomp) -o spiral */
#include <jointcomp/jointcomp.h>

#include <stdio.h>

int main(int argc, char** argv) {
  const char* urdf = NULL;
  const char* parameters = NULL;
  const char* run_names[3] = {"without correction", "stiffness correction", "stiffness and kinematic correction"};
  jc_robot* robot = NULL;
  int32_t has_drives = 0;
  double metrics[15]; /* per run: Ra, Rz, RMS, max, mean (m) */
  int run;

  if (argc == 3) {
    urdf = argv[1];
    parameters = argv[2];
  } else if (argc == 1) {
#ifdef JOINTCOMP_EXAMPLE_DATA_DIR
    urdf = JOINTCOMP_EXAMPLE_DATA_DIR "/robots/rx170.urdf";
    parameters = JOINTCOMP_EXAMPLE_DATA_DIR "/params/rx170.json";
#endif
  }
  if (!urdf) {
    fprintf(stderr, "usage: %s robot.urdf parameters.json\n", argv[0]);
    return 2;
  }
  if (jc_abi_version() != JC_ABI_VERSION) {
    fprintf(stderr, "libjointcomp has ABI %d, this program was built for %d\n", (int)jc_abi_version(), JC_ABI_VERSION);
    return 1;
  }
  if (jc_robot_load(urdf, parameters, &robot) != JC_OK || jc_robot_has_drives(robot, &has_drives) != JC_OK) {
    fprintf(stderr, "%s\n", jc_last_error());
    jc_robot_free(robot);
    return 1;
  }
  /* The flexible-joint plant when the parameters describe the drives, else the quasi-static robot. */
  if (jc_spiral_experiment(robot, has_drives ? 1 : 0, metrics, 15, NULL, 0) != JC_OK) {
    fprintf(stderr, "%s\n", jc_last_error());
    jc_robot_free(robot);
    return 1;
  }
  printf("jointcomp %s: the paper's spiral, simulated robot: %s\n", jc_version(),
         has_drives ? "flexible-joint plant" : "quasi-static");
  printf("%-36s %9s %9s\n", "run", "Ra [mm]", "Rz [mm]");
  for (run = 0; run < 3; ++run) {
    printf("%-36s %9.4f %9.4f\n", run_names[run], metrics[5 * run] * 1e3, metrics[5 * run + 1] * 1e3);
  }
  jc_robot_free(robot);
  return 0;
}
