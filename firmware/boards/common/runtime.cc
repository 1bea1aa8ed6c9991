// The C and C++ runtime pieces an STM32G474 image links without the start files
// (-nostartfiles) and without a heap, shared by the application and the bootloader.
// Each image defines DefaultHandler (its stop-and-reset fault handler).
#include <cstddef>

extern "C" {
[[noreturn]] void DefaultHandler();

// -nostartfiles drops crti/crtn; newlib's __libc_init_array still calls these.
void _init() {}
void _fini() {}
void* __dso_handle = &__dso_handle;

// Firmware objects live for the whole run (main never returns): their destructors are
// never registered. Without this, each global with a destructor would pull in newlib's
// __cxa_atexit, which allocates.
int __aeabi_atexit(void* /*object*/, void (* /*destructor*/)(void*), void* /*dso*/) {
  return 0;
}
}

// No heap, so nothing is ever deleted. The vtables of polymorphic classes (hal::CanPort,
// hal::Flash) still name their deleting destructors, which call operator delete; these
// definitions keep libstdc++'s (and with it free() and the allocator) out of the image,
// and stop the board should one ever be reached.
void operator delete(void* /*pointer*/) noexcept { DefaultHandler(); }
void operator delete(void* /*pointer*/, std::size_t /*bytes*/) noexcept {
  DefaultHandler();
}
