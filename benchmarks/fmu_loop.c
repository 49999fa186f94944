/* The timed loop of a co-simulation master, in C: fmi2DoStep and
 * fmi2GetReal through the FMU's own entry points, every read into its row
 * of a caller's array. peer_common.FmuRun.sample calls it through ctypes
 * (built there with cc), so a study times the FMU as a C importer drives it,
 * not a Python loop's ~1.5 us per communication step.
 *
 * Returns 0 when all `steps` steps and reads succeeded, -1 when the read at
 * the start failed, else the step (1..steps) whose doStep or read failed;
 * *t is the time reached. */
#include <stddef.h>

typedef int (*DoStep)(void *component, double t, double h, int noSetStatePrior);
typedef int (*GetReal)(void *component, const unsigned *references, size_t count, double *values);

int sample(void *do_step, void *get_real, void *component, double step, int steps, const unsigned *references,
           size_t count, double *rows, double *t) {
  DoStep doStep = (DoStep)do_step;
  GetReal getReal = (GetReal)get_real;
  *t = 0.0;
  if (getReal(component, references, count, rows)) return -1;
  for (int i = 1; i <= steps; ++i) {
    if (doStep(component, *t, step, 1) || getReal(component, references, count, rows + (size_t)i * count)) return i;
    *t += step;
  }
  return 0;
}
