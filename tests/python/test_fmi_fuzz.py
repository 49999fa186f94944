"""The FMU under random FMI call sequences (tests/python/fmi_fuzz.py): legal
and illegal orders, hostile values, NULL arrays and fmi2Instantiate variants
over every example FMU, each FMU's sequences in a child process. A bounded
run of about a minute; `bash scripts/fuzz.sh` runs longer ones."""
import os

import fmi_fuzz
from conftest import example_fmus

SECONDS = 45.0  # over all FMUs
# A child that gives no answer within this many seconds is a hang; the
# sanitizer build (scripts/sanitize.sh) runs some 20x slower and sets more.
HANG_SECONDS = float(os.environ.get("MFBD_FUZZ_HANG_SECONDS", "60"))


def test_random_call_sequences_crash_hang_or_break_no_rule():
    seed = int(os.environ.get("MFBD_FUZZ_SEED", "15"))
    fmus = example_fmus()
    assert len(fmus) >= 10
    failures, sequences = [], 0
    for fmu in fmus:
        summary, found = fmi_fuzz.run(fmu, seed, budget=SECONDS / len(fmus), timeout=HANG_SECONDS)
        failures += found
        sequences += summary["sequences"] if summary else 0
    assert not failures, f"seed {seed}:\n" + "\n\n".join(failures)
    assert sequences >= 20 * len(fmus)  # the run did something
