from radioslam.cli import main

main()
