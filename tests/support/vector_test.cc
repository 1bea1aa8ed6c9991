#include "vector_test.h"

namespace mjc::vt {
namespace {

// Constant-initialised, so registration from any static constructor is safe.
Case* g_first = nullptr;
Case* g_last = nullptr;

}  // namespace

Case* FirstCase() { return g_first; }

Registrar::Registrar(Case* c) {
  if (g_last == nullptr) {
    g_first = c;
  } else {
    g_last->next = c;
  }
  g_last = c;
}

}  // namespace mjc::vt
