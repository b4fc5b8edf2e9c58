// ssl-record: captures a live multicast feed into an official SSL log file (.log or .log.gz).
// (Being written: see issue 4.)
int main() { return 1; }
