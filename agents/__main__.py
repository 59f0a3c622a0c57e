from agents.cli import console_main

console_main()
