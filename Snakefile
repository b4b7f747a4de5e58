# jointbench: regenerate every dataset, estimate, figure and table with `snakemake -j2`.
import atexit
import sys
from pathlib import Path

from snakemake.logging import logger
from snakemake.utils import min_version

from jointbench import console, invocation
from jointbench import report as jb_report
from jointbench.configuration import config as jb_config

min_version("8.20")


configfile: "config/config.yaml"


# The report's landing page is written by the report_captions rule (workflow/rules/check.smk).
report: "results/report/workflow.rst"


# The console: one line per job (its rule's message) and the progress, not the scheduler's
# chatter (jointbench.console); the log under .snakemake/log/ keeps everything.
console.install(logger)

# `snakemake --report FILE`: refused while a run would redo a job, whose old results it would
# show (jointbench.report.check_current); once Snakemake has written the report, it gets the
# benchmark's name as its tab title and a style that starts the landing page at the top of the
# window (jointbench.report.finish_report; tests/test_report_browser.py looks at it in Chromium).
_REPORT = jb_report.report_path(sys.argv)
if _REPORT:
    jb_report.check_current(sys.argv)
    atexit.register(jb_report.finish_report, _REPORT)


onstart:
    # A profile's --drop-metadata, which the command line checked as the workflow loaded
    # does not show (refuse_dropped_metadata).
    refuse_dropped_metadata(workflow.execution_settings.keep_metadata)


onsuccess:
    print(jb_report.closing_lines(), file=sys.stderr)


onerror:
    print(jb_report.failure_lines(log), file=sys.stderr)


# Snakemake keeps the last of a --configfile or --config given twice: the run would be made on
# another config than its command line shows (jointbench.invocation.check_options).
invocation.check_options(sys.argv[1:])

# Each config file read again as written (Snakemake's reader takes 010 as 8, keeps the last of
# a key given twice), and the --config values as typed (Python reads 010 as 10). Then the
# project's own schema check before Snakemake's (workflow/rules/common.smk), whose error leads
# with a dump of the schema: a mistake, a misspelt study first, is named in one line with the
# file, or --config, that set it. Snakemake merges the workflow's config file first, then
# each --configfile, then the --config values. Every later check of the config names them too
# (jb_config.sources_named).
_GIVEN_FILES = list(workflow.config_settings.configfiles)
_CONFIG_ARGS = workflow.config_settings.config_args or []
jb_config.check_config_values(_CONFIG_ARGS)
# Snakemake leaves text each value of a --config mapping or list ({trials: 7} gives '7'): each
# is read as a config file holding it would be, and the config holds it so.
CONFIG_VALUES = jb_config.config_values(_CONFIG_ARGS, workflow.config_settings.config)
config.update(jb_config.merged_sources([("", config), ("", CONFIG_VALUES)]))
CONFIG_SOURCES = [
    *jb_config.read_sources(
        [f for f in workflow.configfiles if f not in _GIVEN_FILES] + _GIVEN_FILES
    ),
    (jb_config.CONFIG_VALUES, CONFIG_VALUES),
]
jb_config.check_sources(config, CONFIG_SOURCES)


include: "workflow/rules/common.smk"


rule all:
    default_target: True
    input:
        all_targets(),


# `snakemake -j2 study_cmc` (or study_hinge, study_hip) regenerates one study alone.
for _study in STUDIES:

    rule:
        name:
            f"study_{_study}"
        input:
            study_targets(_study),


include: "workflow/rules/simulate.smk"
include: "workflow/rules/estimate.smk"
include: "workflow/rules/interchange.smk"


# Estimators outside the package: each file of this folder holds the rule of one external
# estimator. Every rule defined while these are read is the user's, whatever folder a file they
# include is in.
USER_RULES = include_user_rules(
    Path(workflow.basedir, "workflow", "rules", "estimators")
)


include: "workflow/rules/render.smk"
include: "workflow/rules/check.smk"
include: "workflow/rules/verdicts.smk"
include: "workflow/rules/sensitivity.smk"


# Once every rule of the package's exists, each of which a rule of the user's may not imitate.
with jb_config.sources_named(CONFIG_SOURCES):
    check_external_rules(USER_RULES)


# Every job of the user's runs under the run's time limit (jobs.external_time_limit_s).
limit_user_jobs(USER_RULES)


# Last, once every rule exists: each job's sources hashed into its parameters, and the files of
# each job of the user's checked as Snakemake plans it; each job given what it checks its code
# against the planned fingerprint with.
track_sources(USER_RULES)
plan_code_checks()


# Files under results/ that Snakemake has no record of are refused: it would take them as current;
# so is a run that would leave such files, or files with another job's record.
refuse_dropped_metadata()
refuse_unrecorded_results()
