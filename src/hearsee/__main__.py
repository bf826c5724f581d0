from hearsee.cli import main

main()
