#pragma once
// Model jobs (issue 4, split in issue 10): fit rigid/face/hand models from a
// corpus and a marker set, and invert them on takes to fill gaps and report
// reconstruction errors. Shared by `csw fit`, `csw invert` and the GUI.
//
//   take_selection.h  --takes syntax (names, ranges, patterns), no corpus needed
//   take_data.h       the selected takes of a corpus, markers in model order
//   model_config.h    the --config file and the model layouts
//   fit_job.h         Fit
//   invert_job.h      Invert
//   model_reports.h   FitText, InvertText, StatsJson
//   parallel_for.h    the thread pool of Invert
//   figures.h         figures through the dlopen'ed module libcsw_figures.so
#include "workbench/jobs/fit_job.h"
#include "workbench/jobs/invert_job.h"
#include "workbench/jobs/model_reports.h"
#include "workbench/jobs/take_selection.h"
