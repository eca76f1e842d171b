echo "cli tests: being written"
