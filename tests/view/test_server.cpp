// The viewer's server (view/server.hpp) without a socket: its origin rule.
#include "view/server.hpp"

#include <gtest/gtest.h>

using namespace softevo;

// The WebSocket's origin check compares with the address the server was started for, never
// with the client's own Host header: a DNS-rebinding page (Origin http://evil.example:PORT,
// Host evil.example:PORT) used to be accepted.
TEST(ViewOrigin, OnlyPagesOfTheBoundAddressMayOpenTheSocket) {
  using view::origin_allowed;
  for (const char* ok : {"http://127.0.0.1:8765", "http://localhost:8765", "http://127.0.0.2:8765",
                         "http://[::1]:8765"})
    EXPECT_TRUE(origin_allowed(ok, "127.0.0.1", 8765)) << ok;
  for (const char* bad :
       {"http://evil.example:8765", "http://127.0.0.1:8766", "https://127.0.0.1:8765",
        "http://127.0.0.1", "http://192.168.1.5:8765", "null", "", "http://127.0.0.1:8765/x",
        "http://localhost.evil.example:8765"})
    EXPECT_FALSE(origin_allowed(bad, "127.0.0.1", 8765)) << bad;
  // Bound to one address of the network: that address, not a name.
  EXPECT_TRUE(origin_allowed("http://10.0.0.7:9000", "10.0.0.7", 9000));
  EXPECT_FALSE(origin_allowed("http://localhost:9000", "10.0.0.7", 9000));
  EXPECT_FALSE(origin_allowed("http://node7.cluster:9000", "10.0.0.7", 9000));
  // Bound to every interface: any address literal or localhost, still no name.
  EXPECT_TRUE(origin_allowed("http://10.0.0.7:9000", "0.0.0.0", 9000));
  EXPECT_TRUE(origin_allowed("http://localhost:9000", "0.0.0.0", 9000));
  EXPECT_FALSE(origin_allowed("http://rebind.evil.example:9000", "0.0.0.0", 9000));
}
