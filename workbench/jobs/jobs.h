#pragma once
// Jobs: every user action as a function taking options, a Progress (with cancel)
// and returning a result. The CLI (workbench/cli) and the GUI (workbench/gui) are
// thin shells over these (architecture.md: "one library, two thin shells").
// One header per job; this one includes them all.
#include "workbench/jobs/export_job.h"
#include "workbench/jobs/import_job.h"
#include "workbench/jobs/info_job.h"
#include "workbench/jobs/inspect_job.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/pack_job.h"
#include "workbench/jobs/simulate_job.h"
