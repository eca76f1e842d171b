// Included once by each executable that feeds OpenImageIO truncated files (the ridge tool, the
// I/O tests). OpenImageIO 2.4's PNG reader leaks one error string per truncated file: its read
// callback calls geterror() and then png_error() longjmps over the string's destructor. Not ours
// to fix; suppressed so the sanitizer build still catches every other leak.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define RIDGELINE_LSAN_SUPPRESSIONS 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RIDGELINE_LSAN_SUPPRESSIONS 1
#endif
#endif
#ifdef RIDGELINE_LSAN_SUPPRESSIONS
extern "C" const char* __lsan_default_suppressions() {
  // Matched on geterror (where the string is allocated): OIIO is built without frame pointers, so
  // the fast unwinder often stops there before reaching PngReadCallback. Also matched on the
  // library itself: where no symbolizer is installed (a fresh machine), frames have no function
  // names and only the module name can match.
  return "leak:PNGInput::PngReadCallback\nleak:ImageInput::geterror\nleak:libOpenImageIO.so\n";
}
#endif
