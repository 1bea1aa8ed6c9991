// Host driver: every registered vector case becomes a GoogleTest test named
// Suite.Name, so ctest, filters and XML reports treat them like any other test.
#include <gtest/gtest.h>

#include "vector_test.h"

namespace {

void GtestSink(const char* file, int line, const char* message) {
  ADD_FAILURE_AT(file, line) << message;
}

class VectorCaseTest : public testing::Test {
 public:
  explicit VectorCaseTest(mjc::vt::Body body) : body_(body) {}
  void TestBody() override {
    mjc::vt::Context context(&GtestSink);
    body_(context);
  }

 private:
  mjc::vt::Body body_;
};

}  // namespace

int main(int argc, char** argv) {
  for (const mjc::vt::Case* c = mjc::vt::FirstCase(); c != nullptr; c = c->next) {
    const mjc::vt::Body body = c->body;
    testing::RegisterTest(
        c->suite, c->name, nullptr, nullptr, c->file, c->line,
        [body]() -> testing::Test* { return new VectorCaseTest(body); });
  }
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
