#pragma once
// What SIGINT (Ctrl-C) and SIGTERM do to an mbi command. mbi run and mbi deform (one pose is a
// trajectory of one frame) make the frame in progress their last and finish their outputs up to
// it (metrics.json and --stats record the signal); before the frames, and in cage, whose outputs
// are all or nothing, a signal ends the process at once. Either way no temporary file stays
// behind, no partial file appears under a final name, and the exit code is 128 + the signal
// (130, 143), as a shell reports a process the signal ended.
#include <atomic>

namespace mbi::cli {

/// Handles SIGINT and SIGTERM from now on. With `stop` (run, deform's frames), the first signal stores its
/// number there and says on stderr that the run stops after the next frame; a second signal, or
/// any signal without `stop`, removes this process's temporary files (io::remove_temporaries_now)
/// and ends the process at once with exit code 128 + signal. SIGXFSZ is ignored: a file past
/// the size limit is a write error (EFBIG), as a full disk is.
void handle_interrupts(std::atomic<int>* stop);

/// A named moment of a command (load, precompute, frame, finish): when the environment variable
/// MBI_TEST_SIGNAL_AT is `stage` (or `stage:TERM`), raises SIGINT (SIGTERM) here, so that the
/// process tests interrupt every stage deterministically. Nothing else reads that variable.
void test_signal_at(const char* stage);

}  // namespace mbi::cli
