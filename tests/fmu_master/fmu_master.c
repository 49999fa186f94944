/* A small FMI 2.0 co-simulation master, the same source for Linux and
 * Windows: loads an FMU binary, instantiates it on an extracted FMU's
 * resources folder (given as a local path, turned into a file URI as an
 * importer does), runs fixed communication steps and prints the time and
 * the requested reals, one row per step, with 17 significant digits.
 *
 * usage: fmu_master BINARY RESOURCES GUID START STOP STEP VR... [VR=VALUE...]
 * A VR=VALUE argument sets that real before initialization (a parameter's or
 * an input's start value); the other VRs are printed.
 * Exit status 0 when every call returned fmi2OK, else 1 (the FMU's log on
 * stderr). With MFBD_MASTER_LOG set (e.g. to logStatistics), logging is on
 * for that category, so benchmarks/architecture_cost.py can read the
 * solver's statistics from stderr. With MFBD_MASTER_TOLERANCE set, that
 * relative tolerance goes to fmi2SetupExperiment. tests/python/
 * test_platforms.py runs it on linux64 and, under Wine, on win64, and
 * compares the rows. */
#define __USE_MINGW_ANSI_STDIO 1 /* C99 printf under MinGW: 17 exact digits */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2FunctionTypes.h"

#ifdef _WIN32
#include <windows.h>
#define LOAD(path) ((void *)LoadLibraryA(path))
#define SYMBOL(lib, name) ((void *)GetProcAddress((HMODULE)(lib), name))
#else
#include <dlfcn.h>
#include <limits.h>
#define LOAD(path) dlopen(path, RTLD_NOW | RTLD_LOCAL)
#define SYMBOL(lib, name) dlsym(lib, name)
#endif

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
  va_list args;
  (void)env;
  fprintf(stderr, "[%s %d %s] ", instance ? instance : "", (int)status, category ? category : "");
  va_start(args, message);
  vfprintf(stderr, message, args);
  va_end(args);
  fputc('\n', stderr);
}

/* file URI of an existing folder: absolute path, '/' separators, a Windows
 * drive after "file:///", every byte outside RFC 3986's unreserved set and
 * '/' ':' percent-escaped. */
static int resourceUri(const char *folder, char *uri, size_t size) {
  char full[4096];
  size_t n = 0;
#ifdef _WIN32
  if (!GetFullPathNameA(folder, sizeof full, full, NULL)) return 0;
  for (char *c = full; *c; ++c)
    if (*c == '\\') *c = '/';
#else
  if (!realpath(folder, full)) return 0;
#endif
  n = (size_t)snprintf(uri, size, "file://%s", full[0] == '/' ? "" : "/");
  for (const unsigned char *c = (const unsigned char *)full; *c && n + 4 < size; ++c) {
    if (isalnum(*c) || strchr("-._~/:", *c))
      uri[n++] = (char)*c;
    else
      n += (size_t)snprintf(uri + n, size - n, "%%%02X", *c);
  }
  uri[n] = '\0';
  return 1;
}

#define FUNCTION(type, name)                                   \
  type name = (type)SYMBOL(lib, #name);                        \
  if (!name) {                                                 \
    fprintf(stderr, "fmu_master: %s not exported\n", #name);   \
    return 1;                                                  \
  }

int main(int argc, char **argv) {
  if (argc < 8) {
    fprintf(stderr, "usage: fmu_master BINARY RESOURCES GUID START STOP STEP VR... [VR=VALUE...]\n");
    return 2;
  }
  void *lib = LOAD(argv[1]);
  if (!lib) {
    fprintf(stderr, "fmu_master: cannot load %s\n", argv[1]);
    return 1;
  }
  FUNCTION(fmi2InstantiateTYPE *, fmi2Instantiate)
  FUNCTION(fmi2SetupExperimentTYPE *, fmi2SetupExperiment)
  FUNCTION(fmi2EnterInitializationModeTYPE *, fmi2EnterInitializationMode)
  FUNCTION(fmi2ExitInitializationModeTYPE *, fmi2ExitInitializationMode)
  FUNCTION(fmi2DoStepTYPE *, fmi2DoStep)
  FUNCTION(fmi2GetRealTYPE *, fmi2GetReal)
  FUNCTION(fmi2SetRealTYPE *, fmi2SetReal)
  FUNCTION(fmi2TerminateTYPE *, fmi2Terminate)
  FUNCTION(fmi2FreeInstanceTYPE *, fmi2FreeInstance)
  FUNCTION(fmi2SetDebugLoggingTYPE *, fmi2SetDebugLogging)

  char uri[8192];
  if (!resourceUri(argv[2], uri, sizeof uri)) {
    fprintf(stderr, "fmu_master: no folder %s\n", argv[2]);
    return 1;
  }
  const double start = atof(argv[4]), stop = atof(argv[5]), step = atof(argv[6]);
  size_t count = 0, starts = 0;
  fmi2ValueReference *references = calloc((size_t)argc, sizeof *references);
  fmi2ValueReference *startReferences = calloc((size_t)argc, sizeof *startReferences);
  double *values = calloc((size_t)argc, sizeof *values), *startValues = calloc((size_t)argc, sizeof *startValues);
  for (int i = 7; i < argc; ++i) {
    char *end = NULL;
    const fmi2ValueReference vr = (fmi2ValueReference)strtoul(argv[i], &end, 10);
    if (*end == '=') {
      startReferences[starts] = vr;
      startValues[starts++] = strtod(end + 1, NULL);
    } else {
      references[count++] = vr;
    }
  }

  const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
  const char *category = getenv("MFBD_MASTER_LOG");
  const fmi2Boolean logging = category && *category ? fmi2True : fmi2False;
  fmi2Component c = fmi2Instantiate("master", fmi2CoSimulation, argv[3], uri, &callbacks, fmi2False, logging);
  if (!c) return 1;
  if (logging && fmi2SetDebugLogging(c, fmi2True, 1, &category) != fmi2OK) return 1;
  const long steps = lround((stop - start) / step);
  const char *tolerance = getenv("MFBD_MASTER_TOLERANCE");
  const fmi2Boolean toleranceDefined = tolerance && *tolerance ? fmi2True : fmi2False;
  int ok = fmi2SetupExperiment(c, toleranceDefined, toleranceDefined ? atof(tolerance) : 0.0, start, fmi2True,
                               stop) == fmi2OK &&
           (starts == 0 || fmi2SetReal(c, startReferences, starts, startValues) == fmi2OK) &&
           fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK;
  for (long n = 0; ok && n <= steps; ++n) {
    const double t = start + (double)n * step;  /* no drift from repeated sums */
    if (n > 0) ok = fmi2DoStep(c, start + (double)(n - 1) * step, step, fmi2True) == fmi2OK;
    if (ok) ok = fmi2GetReal(c, references, count, values) == fmi2OK;
    if (!ok) break;
    printf("%.17g", t);
    for (size_t i = 0; i < count; ++i) printf(" %.17g", values[i]);
    printf("\n");
  }
  if (ok) ok = fmi2Terminate(c) == fmi2OK;
  fmi2FreeInstance(c);
  free(references);
  free(values);
  free(startReferences);
  free(startValues);
  return ok ? 0 : 1;
}
