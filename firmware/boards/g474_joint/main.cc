// The image's main(), which the start-up code calls once the clock tree is up
// (startup.cc): the board (board.cc).
#include "board.h"

int main() { mjc::board::Run(); }
