import grip_env  # noqa: F401  before numpy: it holds numpy at x86-64-v3 (portable_math)
