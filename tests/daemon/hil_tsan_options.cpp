// ThreadSanitizer defaults of the test processes that host umockdev's USB emulation: the HIL
// tests and the daemon tests (scanner_calibration_test). Not of springscand, the HIL tests'
// child, which runs with the plain TSAN_OPTIONS of scripts/test.sh tsan. Only the TSan build
// defines the function.
//
// This process hosts umockdev's USB emulation: a GLib main loop on umockdev's worker thread
// takes over devices, strings, closures and slice memory from the test's main thread. GLib and
// GObject hand them over with GMutex/GCond (futexes) and atomic reference counts compiled into
// those uninstrumented libraries, so TSan sees their frees, memsets and mutex calls through its
// interceptors but not the ordering between them, and reports races inside GLib (seen:
// g_rec_mutex_clear, g_closure_unref, g_type_free_instance, g_slice_alloc0, g_strdup). They
// cannot be suppressed by library name: TSan matches suppressions also against the creation
// stack of each thread in a report, and GLib creates umockdev's worker thread, so such an entry
// would hide every race on that thread, our simulator callbacks included.
// ignore_noninstrumented_modules is TSan's option for exactly this case: it ignores only the
// interceptors called from uninstrumented libraries; every access of our instrumented code,
// on any thread, is still checked.
#if defined(SPRINGSCAN_TSAN)
extern "C" const char* __tsan_default_options() { return "ignore_noninstrumented_modules=1"; }
#endif
