// The fuzz build (MBI_FUZZ=ON) compiles stb_image here, instrumented, instead of linking the
// system's libstb: the sanitizers and the fuzzer's coverage then see inside the PNG decoder
// that mbi::io::parse_png calls. Same header (the system's stb), so the same code.
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image.h>
#include <stb_image_write.h>
