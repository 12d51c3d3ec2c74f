-- By hand, in a real editor: Neovim (0.7 or newer, headless) drives rei-lsp through its
-- built-in LSP client. In a copy of examples/navigation/ run
--   REI_LSP=/path/to/venv/bin/rei-lsp nvim --headless -u NONE -c "luafile nvim_rename.lua"
-- It asks for the references of the floor `start` (a grid cell named in the legend), renames
-- it to `entrance` (room and mission change, and are saved), then tries `waffle` (refused:
-- the robot has that name), and writes what came back to nvim-result.txt.
local out = {}
local function log(s) table.insert(out, s) end
vim.cmd("edit navigation.room")
local buf = vim.api.nvim_get_current_buf()
local id = vim.lsp.start_client({
  name = "rei", cmd = { vim.env.REI_LSP or "rei-lsp" }, root_dir = vim.fn.getcwd(),
})
vim.lsp.buf_attach_client(buf, id)
local client = vim.lsp.get_client_by_id(id)
vim.wait(10000, function() return client.initialized end)
log("initialized: " .. tostring(client.initialized))
log("renameProvider: " .. vim.inspect(client.server_capabilities.renameProvider))
log("referencesProvider: " .. tostring(client.server_capabilities.referencesProvider))
-- the cursor on `start` in:  "S" = floor start
local line = vim.fn.search('= floor start') - 1
local col = vim.fn.getline(line + 1):find("start") - 1
local params = { textDocument = { uri = vim.uri_from_bufnr(buf) }, position = { line = line, character = col },
                 context = { includeDeclaration = true } }
local res = vim.lsp.buf_request_sync(buf, "textDocument/references", params, 10000)
for _, r in pairs(res or {}) do
  for _, loc in ipairs(r.result or {}) do
    log(string.format("reference %s:%d:%d", vim.fn.fnamemodify(vim.uri_to_fname(loc.uri), ":t"), loc.range.start.line + 1, loc.range.start.character + 1))
  end
end
local prep = vim.lsp.buf_request_sync(buf, "textDocument/prepareRename", params, 10000)
for _, r in pairs(prep or {}) do log("prepareRename: " .. vim.inspect(r.result and r.result.placeholder or r.err)) end
params.newName = "entrance"
local ren = vim.lsp.buf_request_sync(buf, "textDocument/rename", params, 10000)
for _, r in pairs(ren or {}) do
  if r.result then
    vim.lsp.util.apply_workspace_edit(r.result, "utf-16")
    for uri, edits in pairs(r.result.changes or {}) do
      log(string.format("rename edits %s: %d", vim.fn.fnamemodify(vim.uri_to_fname(uri), ":t"), #edits))
    end
  else
    log("rename error: " .. vim.inspect(r.err))
  end
end
log("room line now: " .. vim.fn.getline(line + 1))
params.newName = "waffle"
local bad = vim.lsp.buf_request_sync(buf, "textDocument/rename", params, 10000)
for _, r in pairs(bad or {}) do log("clash: " .. ((r.err or r.error) and (r.err or r.error).message or vim.inspect(r.result))) end
vim.fn.writefile(out, "nvim-result.txt")
vim.cmd("wall")
vim.lsp.stop_client(id)
vim.wait(2000, function() return vim.lsp.client_is_stopped(id) end)
vim.cmd("qa!")
