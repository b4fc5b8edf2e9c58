// The translation unit that precompiles the headers every test binary shares
// (sslf_test_headers in tests/CMakeLists.txt): it holds nothing of its own.
