-- Runs test files in the stock lua5.4 interpreter: arg[1] = folder holding ridgeline.so,
-- arg[2] = data folder (with a trailing slash), arg[3..] = files (testlib first).
package.cpath = arg[1] .. "/?.so;" .. package.cpath
ridgeline = require "ridgeline"
DATA = arg[2]
STOCK = true
for i = 3, #arg do dofile(arg[i]) end
print("ok")
