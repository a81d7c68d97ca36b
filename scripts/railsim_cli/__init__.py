"""The commands of ./railsim (run, test, validate, hard-cases, two-hosts, setup); ./railsim installs the Debian
packages and hands over to `python3 -m railsim_cli`."""
