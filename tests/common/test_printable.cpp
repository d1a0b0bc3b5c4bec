// printable(): terminal control sequences from files are shown escaped, text passes unchanged.
#include "common/printable.hpp"

#include <gtest/gtest.h>

#include <string>

using softevo::Newlines;
using softevo::printable;

TEST(Printable, PlainAndUtf8TextPassUnchanged) {
  EXPECT_EQ(printable("node-17.cluster (x86_64) 2026-12-01T10:00:00Z"),
            "node-17.cluster (x86_64) 2026-12-01T10:00:00Z");
  EXPECT_EQ(printable("Gr\xc3\xb6\xc3\x9f"
                      "e \xe2\x86\x92 \xf0\x9f\xa4\x96"),
            "Gr\xc3\xb6\xc3\x9f"
            "e \xe2\x86\x92 \xf0\x9f\xa4\x96");
  EXPECT_EQ(printable(""), "");
}

TEST(Printable, C0ControlsAndDelAreEscaped) {
  // ESC [2J clears the screen, OSC 0 sets the window title, CR rewrites the line.
  EXPECT_EQ(printable("a\x1b[2Jb"), "a\\x1b[2Jb");
  EXPECT_EQ(printable("\x1b]0;owned\x07"), "\\x1b]0;owned\\x07");
  EXPECT_EQ(printable("ok\rFAILED"), "ok\\x0dFAILED");
  EXPECT_EQ(printable(std::string("nul\0x", 5)), "nul\\x00x");
  EXPECT_EQ(printable("del\x7f"), "del\\x7f");
  EXPECT_EQ(printable("two\nlines"), "two\\x0alines");
}

TEST(Printable, NewlinesKeptOnlyWhenAsked) {
  EXPECT_EQ(printable("[run]\nseed = 1\n", Newlines::keep), "[run]\nseed = 1\n");
  EXPECT_EQ(printable("[run]\r\n", Newlines::keep), "[run]\\x0d\n");
}

TEST(Printable, C1ControlsAndMalformedUtf8AreEscaped) {
  EXPECT_EQ(printable("\xc2\x9b"
                      "2J"),
            "\\u009b2J");  // U+009B is CSI on many terminals
  EXPECT_EQ(printable("\xc2\x85"), "\\u0085");
  EXPECT_EQ(printable("\xc2\xa0"), "\xc2\xa0");                      // U+00A0 is printable
  EXPECT_EQ(printable("\x9b"), "\\x9b");                             // a lone continuation byte
  EXPECT_EQ(printable("\xc0\x9b"), "\\xc0\\x9b");                    // overlong
  EXPECT_EQ(printable("\xed\xa0\x80"), "\\xed\\xa0\\x80");           // a surrogate
  EXPECT_EQ(printable("\xe2\x86"), "\\xe2\\x86");                    // truncated
  EXPECT_EQ(printable("\xf4\x90\x80\x80"), "\\xf4\\x90\\x80\\x80");  // above U+10FFFF
}
